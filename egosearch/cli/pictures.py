"""``egosearch pictures``."""

from __future__ import annotations

from egosearch.cli.checks import check_seed
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.scene.layouts import get_scene
from egosearch.sim.pictures import make_pictures


def run(args) -> None:
    check_outputs(dirs={"--out-dir": args.out_dir})
    check_overwrites(dirs={"--out-dir": args.out_dir}, force=args.force)
    check_seed("--seed", args.seed)
    try:
        get_scene(args.layout)
    except ValueError as err:
        raise ValueError(f"--layout: {err}") from None
    for path in make_pictures(args.layout, args.out_dir, seed=args.seed):
        print(path)
