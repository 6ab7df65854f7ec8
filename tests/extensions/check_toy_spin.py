"""The toy searcher's own test (tests/test_toy_spin.py in the copy): `egosearch evaluate` runs it by name."""

from __future__ import annotations

import pandas as pd

from egosearch.cli import main
from egosearch.searchers.searcher_registry import SEARCHERS
from egosearch.sim.scenarios import generate_scenarios, write_scenarios


def test_the_toy_searcher_is_evaluated_by_name_and_only_turns(tmp_path):
    assert SEARCHERS["toy_spin"].bound
    scenarios = tmp_path / "s.csv"
    write_scenarios(scenarios, generate_scenarios("studio", "everywhere", 1.05, n=2, seed=3))
    out = tmp_path / "e.csv"
    assert main(["evaluate", "--policy", "toy_spin", "--scenarios", str(scenarios), "--out", str(out)]) == 0
    rows = pd.read_csv(out)
    assert len(rows) == 2 and (rows["path_length"] < 0.05).all()  # turning on the spot goes nowhere
