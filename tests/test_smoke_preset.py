"""Issue 73 item 3, "smoke means minutes, for every variant": at the smoke preset a variant trains its cpu
learner and levers at toy sizes, whatever steps or episodes it pins, so that any cpu lever is smoke-tested in
minutes; the cost line reads the same capped config (tests/test_estimate.py, tests/test_workflow.py)."""

from __future__ import annotations

import json

import yaml

from egosearch.rl.config import load_config
from egosearch.rl.presets import SMOKE_CAPS
from egosearch.variants import ABLATIONS_DIR, resolve_variant, variant_names


def test_every_stored_variant_at_smoke_is_its_cpu_learner_with_every_size_capped():
    """28 stored variants pin total_env_steps (up to 870k); each trains at most the caps, with its cpu learner, and
    every field the caps leave alone (a lever: bc_weight, the pooled input, the observation) is its cpu value."""
    pinned_steps = []
    for name in variant_names():
        smoke, cpu = resolve_variant(name, "smoke").config, resolve_variant(name, "cpu").config
        assert smoke.algorithm == cpu.algorithm, name
        sizes = {key: getattr(smoke, key) for key in SMOKE_CAPS if hasattr(smoke, key)}
        assert all(value <= SMOKE_CAPS[key] for key, value in sizes.items()), (name, sizes)
        assert all(sizes[key] == min(getattr(cpu, key), SMOKE_CAPS[key]) for key in sizes), name
        levers = {key: value for key, value in cpu.to_dict().items() if key not in SMOKE_CAPS}
        assert {key: smoke.to_dict()[key] for key in levers} == levers, name
        if "total_env_steps" in yaml.safe_load((ABLATIONS_DIR / f"{name}.yaml").read_text()).get("config", {}):
            pinned_steps.append(cpu.total_env_steps)
    assert len(pinned_steps) >= 28 and max(pinned_steps) >= 870_000
    # the stored pair: SAC-DrQ, as at cpu (SAC+CURL before); a variant that pins SAC+CURL keeps it
    assert resolve_variant("head_on", "smoke").config.algorithm == "sac_drq"
    assert resolve_variant("budget_smoke_curl", "smoke").config.algorithm == "sac_curl"
    # the caller's overrides (a test's, a run's seed) and the command line's --set are taken as given, after the caps
    assert resolve_variant("head_on_25px", "smoke", {"total_env_steps": 400}).config.total_env_steps == 400
    assert resolve_variant("head_on_batch128", "smoke").config.batch_size == SMOKE_CAPS["batch_size"]
    assert resolve_variant("head_on_batch128", "smoke", None, {"batch_size": 64}).config.batch_size == 64


def test_the_smoke_preset_alone_is_still_the_unit_tests_toy_sac_curl():
    """load_config("smoke") without a variant stays the toy SAC+CURL the unit tests and the pinned updates build on."""
    cfg = load_config("smoke")
    assert (cfg.algorithm, cfg.total_env_steps, cfg.actor_hidden_dim, cfg.curl_latent) == ("sac_curl", 300, 64, 32)


def test_a_cpu_lever_trains_at_smoke_end_to_end(tmp_path):
    """A bc_weight lever, refused at smoke while smoke's learner was SAC+CURL (which has no cloning term), trains
    there through the CLI as the DAG runs it: its teacher's capped episodes and cloning, then 300 env steps."""
    from egosearch.cli import main

    variant = tmp_path / "head_on_bc_weight_02.yaml"
    data = yaml.safe_load((ABLATIONS_DIR / "head_on.yaml").read_text())
    variant.write_text(yaml.safe_dump({**data, "name": variant.stem, "config": {"bc_weight": 0.2}}))
    out = tmp_path / "run"
    args = ["train", "--variant", str(variant), "--preset", "smoke", "--seed", "0", "--threads", "1", "--out-dir"]
    assert main([*args, str(out)]) == 0
    config = json.loads((out / "config.json").read_text())["config"]
    assert (config["algorithm"], config["bc_weight"], config["total_env_steps"]) == ("sac_drq", 0.2, 300)
    assert (config["demo_episodes"], config["bc_updates"], config["eval_episodes"]) == (2, 20, 2)
    assert (out / "actor.pt").is_file() and (out / "actor_start.pt").is_file()
    rows = (out / "curve.csv").read_text().splitlines()
    assert rows[-1].split(",")[0] == "300", rows[-1]
