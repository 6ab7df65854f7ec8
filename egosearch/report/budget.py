"""The budget study: what a learner setting buys per env step and per core-hour.

One point per learner setting: success at one Table 1 cell (1.05 m, excluding low cabinets by
default), over the setting's seeds with a 95% interval (Wilson for one seed, whose episodes are
independent; with several seeds, which ran the same scenarios, the two-level bootstrap over
scenarios then seeds), against the env steps it
trained for and the core-hours its training took (``wall_s`` of the last row of its curve.csv
times its torch threads: the runs are one-thread jobs, so wall time on a core is core time). Core
time is the machine's: each row names the CPU its runs trained on (``machine``), and where they
trained (``trained_in``: the home layout of their training envs), because a setting read in the
home it trained in alone has an advantage there that is not the setting's.
CSV in, files out: no torch, no simulator.
"""

from __future__ import annotations

import ast
import json
import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

import matplotlib
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter, NullLocator

from egosearch.report.data import output_base, read_curves, read_episodes, suffixed
from egosearch.report.figures import OKABE_ITO, STYLE, save_figure
from egosearch.report.stats import scenario_seed_matrix, two_level_ci, wilson_ci

PathLike = str | os.PathLike

BUDGET_COLUMNS = ("setting", "label", "n_seeds", "env_steps", "core_hours", "core_hours_per_seed", "episodes",
                  "success_rate", "low", "high", "env_steps_per_core_s", "machine", "trained_in")
NOT_RECORDED = "not recorded"


def _done(curve: PathLike) -> dict:
    try:
        done = json.loads((Path(curve).parent / "done.json").read_text())
    except (OSError, ValueError):
        return {}
    return done if isinstance(done, dict) else {}


def run_machine(curve: PathLike) -> str:
    """The CPU that trained the run of ``curve`` (from the ``done.json`` beside it; runs made before
    training recorded it say so), so that core-hours are read against the machine they were spent on."""
    machine = _done(curve).get("machine")
    return (machine.get("cpu") if isinstance(machine, dict) else None) or NOT_RECORDED


def run_layout(curve: PathLike) -> str:
    """The home layout the run of ``curve`` trained in (its ``done.json``'s env kwargs, which it
    records as the repr of their sorted items)."""
    kwargs = _done(curve).get("env_kwargs")
    if isinstance(kwargs, str):
        try:
            kwargs = dict(ast.literal_eval(kwargs))
        except (ValueError, SyntaxError, TypeError):
            kwargs = None
    return str(kwargs.get("layout", NOT_RECORDED)) if isinstance(kwargs, dict) else NOT_RECORDED


def budget_frame(runs: Mapping[str, Iterable[tuple[PathLike, PathLike]]], threads: int = 1,
                 labels: Mapping[str, str] | None = None) -> pd.DataFrame:
    """``runs``: setting -> [(curve.csv, per-episode eval CSV) per seed]. One row per setting."""
    rows = []
    for setting, pairs in runs.items():
        pairs = list(pairs)
        if not pairs:
            raise ValueError(f"budget: setting {setting!r} has no runs")
        curves = read_curves([c for c, _ in pairs])
        last = curves.sort_values("env_steps").groupby("run").tail(1)
        if len(last) != len(pairs) or last["wall_s"].isna().any():
            raise ValueError(f"budget: setting {setting!r}: a curve.csv has no final row with wall_s")
        steps = sorted(set(last["env_steps"].astype(int)))
        if len(steps) != 1:
            raise ValueError(f"budget: setting {setting!r}: its runs end at different env steps {steps}")
        episodes = read_episodes([e for _, e in pairs])
        n, k = len(episodes), int(episodes["success"].sum())
        if episodes["seed"].nunique() > 1:
            _, low, high = two_level_ci(scenario_seed_matrix(episodes, "success")[0])
        else:
            low, high = wilson_ci(k, n)
        core_s = float(last["wall_s"].sum()) * threads
        rows.append({"setting": setting, "label": (labels or {}).get(setting, setting), "n_seeds": len(pairs),
                     "env_steps": steps[0], "core_hours": core_s / 3600,
                     "core_hours_per_seed": core_s / 3600 / len(pairs), "episodes": n,
                     "success_rate": k / n, "low": low, "high": high,
                     "env_steps_per_core_s": steps[0] * len(pairs) / core_s,
                     "machine": " + ".join(sorted({run_machine(c) for c, _ in pairs})),
                     "trained_in": " + ".join(sorted({run_layout(c) for c, _ in pairs}))})
    return pd.DataFrame(rows, columns=list(BUDGET_COLUMNS))


def log_ticks(low: float, high: float, max_ticks: int = 6) -> list[float]:
    """Round tick values (1, 2, 3, 5, else fewer, times a power of ten) inside [low, high], at most
    ``max_ticks`` of them (one per decade when even that is more), on any span, including one
    narrower than a decade, where a plain log axis has no labelled tick."""
    for mantissas in ((1, 2, 3, 5), (1, 2, 5), (1, 3), (1,)):
        ticks = [float(f"{m}e{e}") for e in range(math.floor(math.log10(low)), math.ceil(math.log10(high)) + 1)
                 for m in mantissas if low <= float(f"{m}e{e}") <= high]
        if len(ticks) <= max_ticks:
            return ticks
    return ticks


def budget_figure(df: pd.DataFrame, out_prefix: PathLike, cell: str = "1.05 m, excluding low cabinets",
                  chosen: str | None = None) -> list[Path]:
    """Two panels: success vs env steps (per run) and vs core-hours (per run), one marker per setting
    with its 95% interval; ``chosen`` is drawn filled and named in the legend."""
    base = output_base(out_prefix, "budget")
    df.to_csv(suffixed(base, ".csv"), index=False, float_format="%.6g")
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(7.0, 2.9))
        FigureCanvasAgg(fig)
        axes = fig.subplots(1, 2, sharey=True)
        for i, row in enumerate(df.itertuples(index=False)):
            colour = OKABE_ITO[i % len(OKABE_ITO)]
            label = f"{row.label} ({row.n_seeds} seed{'s' if row.n_seeds > 1 else ''}; trained in {row.trained_in})"
            if row.setting == chosen:
                label += " — chosen"
            for ax, x in zip(axes, (row.env_steps, row.core_hours_per_seed)):
                ax.errorbar([x], [row.success_rate], yerr=[[row.success_rate - row.low], [row.high - row.success_rate]],
                            fmt="o" if row.setting == chosen else "s", color=colour,
                            mfc=colour if row.setting == chosen else "white", ms=6, label=label)
        for ax, values in zip(axes, (df["env_steps"], df["core_hours_per_seed"])):
            low, high = float(values.min()) / 1.4, float(values.max()) * 1.4
            ax.set_xscale("log")
            ax.set_xlim(low, high)
            # The settings may span less than a decade, where a log axis has no labelled tick.
            ax.xaxis.set_major_locator(FixedLocator(log_ticks(low, high)))
            ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v / 1000:g}k" if v >= 1000 else f"{v:g}"))
            ax.xaxis.set_minor_locator(NullLocator())
            ax.xaxis.set_minor_formatter(NullFormatter())
        axes[0].set_xlabel("environment steps per run")
        axes[1].set_xlabel("core-hours per run (training, all in)")
        axes[0].set_ylabel(f"success rate\n({cell})")
        axes[0].set_ylim(-0.02, 1.02)
        handles, labels = axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=2)
        outs = save_figure(fig, base)
    return [suffixed(base, ".csv"), *outs]


__all__ = ["BUDGET_COLUMNS", "NOT_RECORDED", "budget_figure", "budget_frame", "log_ticks", "run_layout", "run_machine"]
