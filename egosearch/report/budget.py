"""The budget study: what a learner setting buys per env step and per core-hour.

One point per learner setting: success at one Table 1 cell (1.05 m, excluding low cabinets by
default), pooled over the setting's seeds with a Wilson 95% interval, against the env steps it
trained for and the core-hours its training took (``wall_s`` of the last row of its curve.csv
times its torch threads: the runs are one-thread jobs, so wall time on a core is core time).
CSV in, files out: no torch, no simulator.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path

import matplotlib
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, NullFormatter

from egosearch.report.data import _with, output_base, read_curves, read_episodes
from egosearch.report.figures import OKABE_ITO, STYLE, _save
from egosearch.report.stats import wilson_ci

PathLike = str | os.PathLike

BUDGET_COLUMNS = ("setting", "label", "n_seeds", "env_steps", "core_hours", "core_hours_per_seed", "episodes",
                  "success_rate", "low", "high", "env_steps_per_core_s")


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
        low, high = wilson_ci(k, n)
        core_s = float(last["wall_s"].sum()) * threads
        rows.append({"setting": setting, "label": (labels or {}).get(setting, setting), "n_seeds": len(pairs),
                     "env_steps": steps[0], "core_hours": core_s / 3600,
                     "core_hours_per_seed": core_s / 3600 / len(pairs), "episodes": n,
                     "success_rate": k / n, "low": low, "high": high,
                     "env_steps_per_core_s": steps[0] * len(pairs) / core_s})
    return pd.DataFrame(rows, columns=list(BUDGET_COLUMNS))


def budget_figure(df: pd.DataFrame, out_prefix: PathLike, cell: str = "1.05 m, excluding low cabinets",
                  chosen: str | None = None) -> list[Path]:
    """Two panels: success vs env steps (per run) and vs core-hours (per run), one marker per setting
    with its 95% interval; ``chosen`` is drawn filled and named in the legend."""
    base = output_base(out_prefix, "budget")
    df.to_csv(_with(base, ".csv"), index=False, float_format="%.6g")
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(7.0, 2.9))
        FigureCanvasAgg(fig)
        axes = fig.subplots(1, 2, sharey=True)
        for i, row in enumerate(df.itertuples(index=False)):
            colour = OKABE_ITO[i % len(OKABE_ITO)]
            label = f"{row.label} ({row.n_seeds} seed{'s' if row.n_seeds > 1 else ''})"
            if row.setting == chosen:
                label += " — chosen"
            for ax, x in zip(axes, (row.env_steps, row.core_hours_per_seed)):
                ax.errorbar([x], [row.success_rate], yerr=[[row.success_rate - row.low], [row.high - row.success_rate]],
                            fmt="o" if row.setting == chosen else "s", color=colour,
                            mfc=colour if row.setting == chosen else "white", ms=6, label=label)
        for ax in axes:
            ax.set_xscale("log")
            ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            ax.xaxis.set_minor_formatter(NullFormatter())
        axes[0].set_xlabel("environment steps per run")
        axes[1].set_xlabel("core-hours per run (training, all in)")
        axes[0].set_ylabel(f"success rate\n({cell})")
        axes[0].set_ylim(-0.02, 1.02)
        handles, labels = axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=2)
        outs = _save(fig, base)
    return [_with(base, ".csv"), *outs]


__all__ = ["BUDGET_COLUMNS", "budget_figure", "budget_frame"]
