"""The Snakemake workflow as the report reads it: its config, the variants ``all`` trains, and which
study a recorded job belongs to and what it cost.

Shared by :mod:`~egosearch.report.readme`, :mod:`~egosearch.report.gpu`, :mod:`~egosearch.report.speed` and the
cost model (:mod:`egosearch.cost`, which prices a run's jobs with :func:`job_cost_s`); it imports none of them.
"""

from __future__ import annotations

from pathlib import Path

import yaml

from egosearch.searchers import searcher_registry as searchers

GENERATED_GROUPS = ("generated_train", "generated_heldout")
"""The generalisation benchmark's groups of generated homes (rules/common.smk's layouts)."""
REPORTS_OUTSIDE_ALL = {"budget": "other", "fresh": "other", "behaviour": "other", "searches": "other",
                       "generalise": "generalise"}


def workflow_config() -> dict:
    """The experiment list the Snakefile reads (``egosearch/workflow/config.yaml``)."""
    return yaml.safe_load((Path(__file__).resolve().parent.parent / "workflow" / "config.yaml").read_text())


BOUND_SEEDS = (0,)
"""The seeds the reference searchers run (they learn nothing: one seed)."""


def bound_eval_files(results: str | Path, homes, placements, heights, bounds=None, seeds=BOUND_SEEDS) -> list[str]:
    """The reference searchers' evaluation CSVs in the DAG's order: bound, seed, home, placement,
    height, as Snakemake's ``expand`` lists them. The rules and ``egosearch report regenerate`` both
    take this list, so the reports read their inputs in one order and write the same bytes. ``bounds``:
    Table 1's (:func:`egosearch.searchers.searcher_registry.bounds`) unless given."""
    bounds = searchers.bounds() if bounds is None else bounds
    return [f"{results}/eval/{bound}/seed{seed}/{home}/{placement}/h{height}.csv" for bound in bounds
            for seed in seeds for home in homes for placement in placements for height in heights]


def workflow_heights(config: dict) -> list[str]:
    """The Table 1 heights as the output paths spell them (``0.45``, not ``0.450``)."""
    return [f"{h:g}" for h in config["heights"]]


def claims_pairs(config: dict) -> list[list[str]]:
    """The pairs the claims are read on at the config's preset: its own ``claims_pairs``, else the top
    level's."""
    preset = config.get("presets", {}).get(config.get("preset"), {})
    return preset.get("claims_pairs", config.get("claims_pairs", []))


def preset_seeds(config: dict, preset: str | None = None) -> list[int]:
    """The training seeds ``all`` trains and Table 1 reads at ``preset`` (the config's own preset unless
    given): the preset's ``seeds``. Its ``spread_seeds`` beyond them (the reference's, trained for
    `snakemake seed_spread`) are no part of ``all`` or of its tables."""
    preset = preset or config["preset"]
    if preset not in config["presets"]:
        raise ValueError(f"preset {preset!r} is not in the config; its presets: {', '.join(config['presets'])}")
    return list(config["presets"][preset]["seeds"])


def variants_of_all(config: dict | None = None) -> list[str]:
    """The variants `snakemake all` trains, in the DAG's order (comparisons train others)."""
    config = config or workflow_config()
    return list(dict.fromkeys(config["variants"] + [config["reference_variant"]]))


def job_study(job: dict, config: dict | None = None, preset: str | None = None) -> str:
    """Which command a recorded job belongs to: "all", "generalise", or "other" (comparisons,
    the budget study, the fresh-set check, the traces, the spread seeds). ``preset``: the one the job
    ran at (a provenance record's ``preset``), the config's own unless given; its seeds
    (:func:`preset_seeds`) are those ``all`` and ``generalise`` train (a preset the config does not
    list has no known seeds: every seed counts). A policy's job (``train``, ``eval``, ``eval_start``:
    ``variant/seedN/...``) is of ``all`` only for a variant of ``all`` (:func:`variants_of_all`) at one
    of those seeds; a start's evaluation (``eval_start``, what learning adds) is of ``all`` for those
    variants alone, never of ``generalise``; a searcher's (``bound``) only for Table 1's bound rows."""
    config = config or workflow_config()
    of_all = set(variants_of_all(config))
    generalise_only = set(config.get("generalise", {}).get("variants", [])) - of_all
    rule, parts = job["rule"], job["job"].split("/")
    if rule in ("fresh", "traces"):
        return "other"
    if rule == "report":
        return REPORTS_OUTSIDE_ALL.get(parts[0], "all")
    if any(part in GENERATED_GROUPS for part in parts):
        return "generalise"
    if rule == "bound":  # a Table 1 bound's evaluation is of all; another searcher's (a memory window, a floor) not
        return "all" if parts[0] in searchers.bounds() else "other"
    if rule in ("train", "eval", "eval_start"):
        if (preset or config["preset"]) in config["presets"]:
            seeds = {f"seed{seed}" for seed in preset_seeds(config, preset)}
            if len(parts) < 2 or parts[1] not in seeds:
                return "other"
        if parts[0] in of_all:
            return "all"
        return "generalise" if rule != "eval_start" and parts[0] in generalise_only else "other"
    return "all"


def job_cost_s(job: dict) -> float:
    """What a one-thread job costs a core of its own: its CPU time where the benchmark recorded it,
    else its wall time. A job that ran beside more jobs than cores waited for a core part of its wall
    time (three trainings on two cores take half as long again each). A resumed training's benchmark
    timed only its last part: its cost is scaled to the whole run by wall time (``run_wall_s``),
    which assumes the earlier part spent its wall time on the CPU in the same proportion."""
    cpu = job.get("cpu_s")
    cost = float(cpu) if cpu is not None and 0 < cpu <= job["wall_s"] else float(job["wall_s"])
    run_wall = job.get("run_wall_s")
    if run_wall is not None and run_wall > job["wall_s"] > 0:
        cost *= run_wall / job["wall_s"]
    return cost
