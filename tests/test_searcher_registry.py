"""The registry of searchers that are not learned (egosearch.searchers.searcher_registry): a searcher registered from
outside egosearch (a toy defined here, that only turns) is run by ``egosearch evaluate``, tabled by Table 1 as a
bound row, and refused by name once gone, with no other list to edit; the registered searchers are today's."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest

from egosearch.cli import main
from egosearch.report.commands import cmd_table1, group_bounds
from egosearch.report.tables import bound_names
from egosearch.report.workflow_jobs import bound_eval_files
from egosearch.searchers import searcher_registry as registry
from egosearch.sim.body_envs import ENV_IDS
from egosearch.sim.scenarios import generate_scenarios, write_scenarios
from egosearch.variants import VariantError, new_variant

TOY = "toy_turner"
TOY_LABEL = "toy searcher that only turns"
TOY_WHAT = "turns on the spot at full rate, every step"
CELL = ("studio", "everywhere", 1.05)


class AlwaysTurns:
    """The smallest searcher: every step a full turn to the left and nothing else."""

    made_for: list[bool] = []  # the head of each env it was made for
    actions: list[np.ndarray] = []

    def __init__(self, env):
        self.action_dim = env.action_space.shape[0]
        AlwaysTurns.made_for.append(env.unwrapped.spec_agent.head)

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, obs: dict) -> np.ndarray:
        action = np.zeros(self.action_dim, np.float32)
        action[2] = 1.0  # forward, lateral, turn[, pitch, yaw]
        AlwaysTurns.actions.append(action)
        return action


@pytest.fixture
def toy():
    """The toy registered as a Table 1 bound (its rows after the policy's) for one test, gone after it."""
    AlwaysTurns.made_for.clear()
    AlwaysTurns.actions.clear()
    searcher = registry.register(TOY, AlwaysTurns, env_id="EgoSearchNoHead-v0", head=False, label=TOY_LABEL,
                                 what=TOY_WHAT, help="a toy", bound=True)
    yield searcher
    registry.SEARCHERS.pop(TOY, None)


def _cli_line(capsys, *argv) -> tuple[int, str]:
    code = main(list(argv))
    captured = capsys.readouterr()
    lines = [line for line in captured.err.splitlines() if not line.startswith("pybullet build time")]
    return code, "\n".join(lines) if code else captured.out


SHIPPED = ("random", "oracle", "frontier", "frontier_head_off", "frontier_tuned", "frontier_tuned_head_off",
           "modular_random", "modular_random_head_off")
"""The searchers the package ships, in registration order. A user's own, registered after them, may join
(these tests read the registry, not this list, for everything else)."""


def _in_order(shipped: tuple[str, ...], listed: tuple[str, ...]) -> tuple[str, ...]:
    """``listed`` as far as it names shipped searchers: what a user's own registration must not reorder."""
    return tuple(name for name in listed if name in shipped)


def test_the_shipped_searchers_are_registered_and_agree_with_their_envs():
    assert _in_order(SHIPPED, registry.names()) == SHIPPED
    # Table 1's rows, in order: the floor, the classical searchers (the untuned, then the tuned), the ceiling
    bounds = registry.bounds()
    assert _in_order(SHIPPED, bounds) == ("random", "frontier", "frontier_head_off", "frontier_tuned",
                                          "frontier_tuned_head_off", "oracle")
    rows = [registry.get(name).table_row for name in bounds]
    assert rows == sorted(rows, key=registry.TABLE_ROWS.index)  # every floor first, every ceiling last
    assert _in_order(SHIPPED, registry.classical()) == ("frontier", "frontier_head_off", "frontier_tuned",
                                                        "frontier_tuned_head_off")
    assert registry.modular_floors() == {"EgoSearchModular-v0": "modular_random",
                                         "EgoSearchNoHeadModular-v0": "modular_random_head_off"}
    for searcher in registry.SEARCHERS.values():
        assert searcher.env_id in ENV_IDS, searcher  # a body env: every searcher acts at the body's steps
        assert searcher.head in (None, ENV_IDS[searcher.env_id]["head"]), searcher
        assert callable(searcher.policy_factory()), searcher
        assert searcher.label and searcher.what, searcher
    # a bound without a line style of its own is drawn in the path-length figure's default one
    from egosearch.report.pathlength import DEFAULT_STYLE, searcher_style

    assert searcher_style("frontier") == registry.get("frontier").path_style
    assert searcher_style("modular_random") == DEFAULT_STYLE


def test_a_name_is_registered_once_and_never_as_actor(toy):
    with pytest.raises(ValueError, match="registered already"):
        registry.register(TOY, AlwaysTurns)
    with pytest.raises(ValueError, match="'actor' is reserved: --policy actor is a trained actor"):
        registry.register("actor", AlwaysTurns)
    with pytest.raises(ValueError, match="table_row='middle'; allowed: floor, beside, ceiling"):
        registry.register("toy_other", AlwaysTurns, table_row="middle")
    assert "toy_other" not in registry.SEARCHERS


def test_a_registered_searcher_is_evaluated_by_the_cli_and_tabled_as_a_bound(toy, tmp_path, capsys):
    home, placement, height = CELL
    scenarios = tmp_path / "results" / "smoke" / "scenarios" / home / placement / f"h{height:g}.csv"
    scenarios.parent.mkdir(parents=True)
    write_scenarios(scenarios, generate_scenarios(home, placement, height, n=2, seed=3))
    out = tmp_path / "results" / "smoke" / "eval" / TOY / "seed0" / home / placement / f"h{height:g}.csv"
    with pytest.raises(SystemExit):
        main(["evaluate", "--help"])
    assert f"{TOY} (a toy)" in " ".join(capsys.readouterr().out.split())  # however argparse wraps it

    code, said = _cli_line(capsys, "evaluate", "--policy", TOY, "--scenarios", str(scenarios), "--out", str(out))
    assert code == 0, said
    assert f"{TOY}: success" in said and "over 2 episodes" in said
    # made by its factory for its own env (the head fixed), and it did what it does: turn, every step
    assert AlwaysTurns.made_for == [False] and len(AlwaysTurns.actions) >= 2
    assert all(a.tolist() == [0.0, 0.0, 1.0] for a in AlwaysTurns.actions)
    episodes = pd.read_csv(out)
    assert len(episodes) == 2

    # Table 1: the toy is a bound row, after the policy and before the oracle, with its words in the note
    ours = tmp_path / "results" / "smoke" / "eval" / "head_on" / "seed0" / home / placement / f"h{height:g}.csv"
    ours.parent.mkdir(parents=True)
    episodes.assign(success=1, spl=0.5).to_csv(ours, index=False)
    oracle = out.parents[4] / "oracle" / "seed0" / home / placement / out.name
    oracle.parent.mkdir(parents=True)
    episodes.assign(success=1, spl=1.0).to_csv(oracle, index=False)
    # before it has run, the bound changes no table: no columns, no row, and the same bytes as without it
    before = cmd_table1([ours], tmp_path / "before" / "table1", variant="head_on", bounds=[oracle])
    assert not [c for c in before.columns if c.startswith(TOY)]
    registry.unregister(TOY)
    cmd_table1([ours], tmp_path / "without" / "table1", variant="head_on", bounds=[oracle])
    for suffix in ("csv", "md", "tex"):
        assert ((tmp_path / "before" / f"table1.{suffix}").read_bytes()
                == (tmp_path / "without" / f"table1.{suffix}").read_bytes()), suffix
    registry.register(TOY, AlwaysTurns, env_id="EgoSearchNoHead-v0", head=False, label=TOY_LABEL, what=TOY_WHAT,
                      help="a toy", bound=True)
    df = cmd_table1([ours], tmp_path / "figs" / "table1", variant="head_on", bounds=[out, oracle])
    assert df.loc[0, f"{TOY}_n_episodes"] == 2
    assert df.loc[0, f"{TOY}_success_rate"] == episodes["success"].mean()
    md = (tmp_path / "figs" / "table1.md").read_text()
    rows = [line.split(" | ")[1] for line in md.splitlines() if line.startswith("| 1.05m")]
    assert rows == ["random searcher", "ours (head_on)", TOY_LABEL, "privileged oracle", "paper"], rows
    assert f"{TOY_LABEL[0].upper() + TOY_LABEL[1:]}: {TOY_WHAT}, 2 episodes per cell" in md
    assert TOY_LABEL in (tmp_path / "figs" / "table1.tex").read_text()
    # the workflow's bound files name it too
    assert any(f"/eval/{TOY}/" in p for p in bound_eval_files("results/smoke", [home], [placement], ["1.05"]))

    # registered as no bound, it is no Table 1 row: its files are refused there
    registry.register(TOY, AlwaysTurns, env_id="EgoSearchNoHead-v0", head=False, label=TOY_LABEL, what=TOY_WHAT,
                      replace=True)
    assert TOY not in registry.bounds()
    with pytest.raises(ValueError, match="not a reference searcher's evaluation .*" +
                       re.escape("{" + "|".join(bound_names()) + "}")):
        group_bounds([out])


def test_an_unknown_or_unregistered_name_is_refused_in_one_line(toy, tmp_path, capsys):
    with pytest.raises(ValueError) as err:
        registry.get("toy_typo")
    assert str(err.value) == f"unknown searcher 'toy_typo'; registered: {', '.join(registry.names())}"
    assert TOY in str(err.value) and "\n" not in str(err.value)

    scenarios = tmp_path / "s.csv"
    write_scenarios(scenarios, generate_scenarios(*CELL, n=1, seed=3))
    for name in ("toy_typo", TOY):
        if name == TOY:
            registry.unregister(TOY)
        code, said = _cli_line(capsys, "evaluate", "--policy", name, "--scenarios", str(scenarios), "--out",
                               str(tmp_path / "o.csv"))
        assert code == 2
        assert said == (f"egosearch evaluate: error: --policy={name!r}; allowed: {', '.join(registry.names())}, "
                        "actor"), said
    assert not (tmp_path / "o.csv").exists()


def test_a_variant_may_not_take_a_registered_searchers_name(toy, tmp_path):
    with pytest.raises(VariantError, match=f"variant name '{TOY}' is a reference searcher's.*{TOY}\\)"):
        new_variant(TOY, directory=tmp_path)


def test_both_registries_are_one_helper_and_answer_alike():
    """The learners' and the searchers' registries keep their entries in the one helper's dict
    (egosearch.core.named_registry): an unknown name is the same one line in each, and a name that could not name a
    folder is refused by both."""
    from egosearch.core.named_registry import Registry
    from egosearch.rl import learner_registry as learners

    assert learners.LEARNERS is learners._REGISTRY.entries and registry.SEARCHERS is registry._REGISTRY.entries
    with pytest.raises(ValueError, match=r"^unknown algorithm 'nope'; registered: sac_curl, sac_drq, "):
        learners.learner("nope")
    with pytest.raises(ValueError, match=r"^unknown searcher 'nope'; registered: random, oracle, "):
        registry.get("nope")
    for register in (lambda n: learners.register(n, "x", "m:a"), lambda n: registry.register(n, AlwaysTurns)):
        with pytest.raises(ValueError, match="letters, digits, '_' and '-' only"):
            register("a/b")
    own = Registry("thing")
    own.add("one", 1)
    with pytest.raises(ValueError, match=r"^thing 'one' is registered already$"):
        own.add("one", 2)
    assert own.add("one", 3, replace=True) == 3 and own.names() == ("one",) and own.remove("one") == 3
    with pytest.raises(ValueError, match="unknown thing 'one'; registered: $"):
        own.remove("one")
