"""``egosearch pictures``."""

from __future__ import annotations

from egosearch.core.outputs import check_outputs
from egosearch.sim.pictures import make_pictures


def run(args) -> None:
    check_outputs(dirs={"--out-dir": args.out_dir})
    for path in make_pictures(args.layout, args.out_dir, seed=args.seed):
        print(path)
