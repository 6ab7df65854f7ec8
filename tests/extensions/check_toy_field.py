"""The toy SAC-DrQ field's own test (tests/test_toy_field.py in the copy)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from egosearch.rl.config import LearnerConfig, config_sources, load_config, own_settings

STORED = Path(__file__).resolve().parents[1] / "results" / "cpu" / "train" / "head_on" / "seed0" / "config.json"


def test_the_field_is_sac_drqs_own_shown_and_defaulted_for_runs_stored_before_it():
    assert "toy_q_clip" in own_settings("sac_drq") and "toy_q_clip" not in own_settings("sac_curl")
    assert load_config("cpu", {"toy_q_clip": 1.5}).toy_q_clip == 1.5
    row = next(r for r in config_sources("sac_drq", "cpu") if r["field"] == "toy_q_clip")
    assert row["source"] == "default"
    stored = json.loads(STORED.read_text())["config"]
    assert stored["algorithm"] == "sac_drq" and "toy_q_clip" not in stored
    assert LearnerConfig.from_stored(stored).toy_q_clip == 0.0
    with pytest.raises(ValueError, match="toy_q_clip"):
        load_config("paper", {"toy_q_clip": 1.0})  # SAC+CURL has no such field: one line
