"""Every variant file in ablations/ loads, and a bad one is one clear line."""

import re

import pytest

from egosearch.variants import ABLATIONS_DIR, VariantError, load_variant, variant_names


@pytest.mark.parametrize("name", variant_names())
def test_every_ablation_file_loads_and_its_config_validates(name):
    from egosearch.rl.config import load_config

    variant = load_variant(name)
    assert variant.name == name
    for preset in ("smoke", "cpu", "paper"):  # `egosearch variant check` checks all three
        load_config(preset, variant.config)


@pytest.mark.parametrize("name", variant_names())
def test_a_pin_holds_a_value_the_cpu_profile_no_longer_has(name):
    """``# pinned`` marks a config line kept for the variant's stored runs after the cpu preset moved; a pin
    on the preset's own value changes nothing, and a file of such pins no longer says what it changes."""
    from egosearch.rl.config import load_config

    cpu = load_config("cpu", {})
    config = load_variant(name).config
    pinned = re.findall(r"^  (\w+):[^#\n]*#\s*pinned", (ABLATIONS_DIR / f"{name}.yaml").read_text(), re.MULTILINE)
    assert all(key in config for key in pinned), pinned
    assert not [key for key in pinned if getattr(cpu, key) == config[key]], "the cpu preset's own value again"


def test_a_new_cpu_training_reads_its_curve_on_100_scenarios_and_keeps_its_actor_every_50k(tmp_path):
    """The memory issue's Figure 6: 100 scenarios a point per seed (75 resolve a rise of 0.10 on 3 seeds), and
    the actor kept at 50k, 100k, 150k and 200k env steps. A variant that pins nothing takes both."""
    from egosearch.variants import resolve_variant

    (tmp_path / "fresh_lever.yaml").write_text("name: fresh_lever\nenv_id: EgoSearch-v0\ntrain_env: "
                                               "{layout: paper_homes, placement: everywhere}\n")
    cfg = resolve_variant(load_variant("fresh_lever", tmp_path), "cpu").config
    assert cfg.eval_episodes >= 100
    snapshots = list(range(cfg.actor_snapshot_every, cfg.total_env_steps + 1, cfg.actor_snapshot_every))
    assert snapshots == [50_000, 100_000, 150_000, 200_000]


@pytest.mark.parametrize("side", ["head_on", "head_off"])
def test_the_stored_pair_trains_as_the_variant_its_runs_were_made_as(side):
    """head_on's and head_off's stored runs were trained as *_curve100 and copied: the two resolve alike."""
    from egosearch.variants import resolve_variant

    stored, made_as = resolve_variant(side, "cpu"), resolve_variant(f"{side}_curve100", "cpu")
    assert stored.env_id == made_as.env_id and stored.train_env == made_as.train_env
    assert stored.config.to_dict() == made_as.config.to_dict()


def test_bad_variant_files(tmp_path):
    (tmp_path / "typo.yaml").write_text("name: typo\nenv_id: EgoSearch-v1\ntrain_env: {layout: kitchen_living, "
                                        "placement: everywhere}\n")
    with pytest.raises(VariantError, match="env_id"):
        load_variant("typo", tmp_path)
    (tmp_path / "wrongname.yaml").write_text("name: other\nenv_id: EgoSearch-v0\ntrain_env: {layout: kitchen_living, "
                                             "placement: everywhere}\n")
    with pytest.raises(VariantError, match="must equal the file name"):
        load_variant("wrongname", tmp_path)
    with pytest.raises(VariantError, match="allowed: typo, wrongname"):
        load_variant("missing", tmp_path)


# Fields that change how fast or how often a run reports, not what it learns.
NOT_LEARNING = {"num_threads", "device", "compile", "cuda_graph", "channels_last", "share_encoder_forward",
                "eval_episodes", "eval_every", "log_every", "checkpoint_every", "keep_checkpoint", "seed",
                "actor_snapshot_every"}
REPO = __import__("pathlib").Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("run", sorted(str(p.parent.relative_to(REPO)) for p in
                                       (REPO / "results").glob("*/train/*/seed*/config.json")))
def test_a_stored_training_is_what_its_variant_file_says_at_its_preset(run):
    """So a preset that changes pins the old values in the files of the runs stored before it (as
    head_on_25px does): otherwise `compare` would read a stored run as the variant's, trained otherwise."""
    import json

    from egosearch.rl.config import field_defaults, load_config

    _, preset, _, name, _ = run.split("/")
    stored = json.loads((REPO / run / "config.json").read_text())
    want = load_config(preset, load_variant(name).config).to_dict()
    got = field_defaults() | stored["config"]
    # runs from before target_memory was a learner field name the memory in their env id
    got["target_memory"] = got["target_memory"] or any(m in stored["env_id"] for m in ("Memory", "Map"))
    got["modular_searcher"] = got["modular_searcher"] or "Modular" in stored["env_id"]
    differ = {k: (got[k], v) for k, v in want.items() if k not in NOT_LEARNING and got[k] != v}
    assert not differ, f"{run}: stored, variant file: {differ}"


def test_a_resolved_variant_is_the_training_run_the_gpu_check_reads():
    """rl/bench_learner.py names what it reads of a resolved variant (TrainingRun), not importing the layer above."""
    from egosearch.rl.bench_learner import TrainingRun
    from egosearch.variants import resolve_variant

    run = resolve_variant("head_on", "smoke")
    assert isinstance(run, TrainingRun)
    # at smoke, head_on's cpu learner: its observation has the last-seen target memory
    assert (run.name, run.env_id, run.train_env["layout"]) == ("head_on", "EgoSearchMemory-v0", "paper_homes")
