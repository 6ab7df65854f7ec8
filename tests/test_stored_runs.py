"""Every stored training resolves to the config it ran with: its variant file, on the preset as it is
today, gives the same learner config and env id as the run's ``done.json``. A preset that moves must pin
the moved fields in the variant files of the runs stored before it, or this fails (and the DAG would
refuse to resume, or silently compare a run against a config it never had)."""

import json
from pathlib import Path

import pytest

from egosearch.rl.run_files import CheckpointError, check_same_run, saved_config
from egosearch.variants import ABLATIONS_DIR, resolve_variant

ROOT = Path(__file__).resolve().parents[1]
STORED = sorted((ROOT / "results" / "cpu" / "train").glob("*/seed*/done.json"))


def test_there_are_stored_trainings():
    assert len(STORED) > 20


@pytest.mark.parametrize("done", STORED, ids=lambda p: f"{p.parent.parent.name}/{p.parent.name}")
def test_stored_training_resolves_to_its_config(done):
    saved = json.loads(done.read_text())
    variant = done.parent.parent.name
    assert (ABLATIONS_DIR / f"{variant}.yaml").exists(), f"{variant}: a stored training without a variant file"
    resolved = resolve_variant(variant, "cpu", {"seed": saved["config"]["seed"]})
    # the name a run was trained under may differ (a lever promoted to its stored name): compare the rest
    check_same_run("stored run", done, saved, saved["variant"], resolved.env_id, resolved.train_env, resolved.config)


def test_a_moved_preset_field_is_caught(tmp_path):
    done = next(p for p in STORED if p.parent.parent.name == "head_on_imitation_finetune")
    saved = json.loads(done.read_text())
    resolved = resolve_variant("head_on_imitation_finetune", "cpu", {"seed": saved["config"]["seed"],
                                                                     "eval_every": 1234})
    with pytest.raises(CheckpointError, match="eval_every=20000"):
        check_same_run("stored run", done, saved, saved["variant"], resolved.env_id, resolved.train_env,
                       resolved.config)


def test_a_run_stored_before_a_field_existed_ran_as_its_default():
    saved = {"variant": "v", "env_id": "EgoSearchMemory-v0", "config": {"seed": 0}}
    theirs = saved_config(saved)
    assert theirs["demo_episodes"] == 0 and theirs["bc_weight"] == 0.0
    assert theirs["target_memory"] is True and theirs["modular_searcher"] is False


CONFIGS = sorted((ROOT / "results").glob("*/train/*/seed*/config.json"))


def test_there_are_stored_configs():
    assert len(CONFIGS) >= len(STORED)


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: "/".join(p.parts[-5:-1]))
def test_a_stored_config_loads_as_its_learners_config_with_the_values_it_recorded(path):
    """Every stored config.json loads as its learner's config (run settings + its own), each field it has at
    the recorded value (or, recorded before the field existed, at its default, its "off"). What the file
    records beyond them are other learners' fields, which this learner never read (runs stored before the
    config was split into a config per learner recorded every learner's)."""
    from egosearch.rl.config import LearnerConfig, field_defaults

    saved = json.loads(path.read_text())
    recorded = saved_config(saved)
    cfg = LearnerConfig.from_stored(recorded)
    mine = cfg.to_dict()
    assert {k: recorded.get(k, field_defaults()[k]) for k in mine} == mine
    assert set(recorded) - set(mine) <= set(field_defaults()), "a recorded field no settings class has"
    # and the stored file's own values, read back
    assert all(mine[k] == v for k, v in saved["config"].items() if k in mine)
