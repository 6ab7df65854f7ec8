"""Every stored training resolves to the config it ran with: its variant file, on the profile as it is
today, gives the same learner config and env id as the run's ``done.json``. A profile that moves must pin
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


def test_a_moved_profile_field_is_caught(tmp_path):
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
