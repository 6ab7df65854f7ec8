"""The Snakemake suite: dry run, lint, schema, a smoke run of table1, and a cluster executor."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

REPO = Path(__file__).resolve().parent.parent
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
PRESET_CORES = yaml.safe_load((REPO / "profiles/default/config.yaml").read_text())["jobs"]
"""The cores a run on this machine that names none runs on (the workflow profile's jobs, which Snakemake reads
as cores there), dry runs' cost lines included."""


def run(args, cwd=REPO, timeout=600):
    return subprocess.run(SNAKEMAKE + args, cwd=cwd, capture_output=True, text=True, timeout=timeout)


@pytest.fixture
def checkout(tmp_path):
    """A copy of the suite (no results), so that runs never touch the stored results."""
    files = subprocess.run(["git", "ls-files"], cwd=REPO, capture_output=True, text=True).stdout.split()
    dest = tmp_path / "suite"
    for name in files:
        if name.startswith(("results/", "paper_figs/")):
            continue
        src = REPO / name
        if src.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name)
    return dest


def test_dry_run_of_all_lists_every_stage():
    out = run(["-n", "all", "--quiet", "rules", "--config", "preset=smoke"])
    assert out.returncode == 0, out.stderr
    for rule in ("scenarios", "train", "evaluate", "fullbody", "fullbody_oracle", "table1", "table2", "fig6", "fig7",
                 "fig7_oracle", "pathlength", "provenance"):
        assert rule in out.stdout, rule


def test_snakemake_all_as_the_user_types_it():
    """Issue 57: `snakemake -n all`, verbatim (no --cores), plans on this machine; on a complete tree (the
    stored results) it has nothing to do, and prints no fresh clone's estimate above "Nothing to be done"."""
    out = run(["-n", "all"])
    text = out.stdout + out.stderr
    assert out.returncode == 0, text[-3000:]
    assert "cores have to be specified" not in text
    if "Nothing to be done" in text:
        assert "from a fresh clone" not in text and "simulated on" not in text, text[:3000]


def test_a_run_as_the_user_types_it_runs_on_this_machine(checkout):
    """`snakemake table2` with no --cores runs (it used to stop: "cores have to be specified for local
    execution"), on the preset's 2 cores; --jobs is still read as the cores on one machine."""
    out = run(["table2", "--config", "preset=smoke"], cwd=checkout)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    assert f"Provided cores: {PRESET_CORES}" in out.stdout + out.stderr
    assert (checkout / "paper_figs/smoke/table2.md").is_file()
    planned = run(["-n", "screen", "-j", "6", "--config", "variant=head_off"])
    assert planned.returncode == 0 and "on 6 core(s)" in planned.stderr, planned.stderr[-3000:]


def test_a_cluster_executors_dry_run_names_no_cores_of_this_machine():
    """The preset's jobs are cores on this machine only: under a cluster executor they are the jobs it
    submits at once, and the cost line says it has no cores here to lay the jobs out on."""
    assert PRESET_CORES == 2
    out = run(["-n", "screen", "--config", "variant=head_off", "--executor", "cluster-generic",
               "--cluster-generic-submit-cmd", "true", "--jobs", "50"])
    assert out.returncode == 0, out.stderr[-3000:]
    assert "(no estimate of the cost: a cluster executor's run lays its jobs out itself, on no cores of this " \
           "machine to simulate)" in out.stderr.splitlines()
    assert "core(s)" not in out.stderr


def test_dry_run_of_generalise_reads_four_groups_of_homes():
    out = run(["-n", "generalise", "--config", "preset=smoke"])
    assert out.returncode == 0, out.stderr
    text = out.stdout + out.stderr
    for group in ("generated_heldout", "generated_train", "kitchen_living", "bedroom_bath"):
        assert f"eval/head_on_generated_homes/seed0/{group}/everywhere/h1.05.csv" in text, group
    assert "group_scenarios" in text and "home900000:900020" not in text  # the homes go to the command
    assert "generalise" not in run(["-n", "all", "--quiet", "rules", "--config", "preset=smoke"]).stdout


def test_the_budget_study_reads_its_settings_against_the_presets_reference():
    # Every setting with its seed 0, the preset's own (the reference variant) with all its seeds;
    # the settings trained in kitchen_living alone are one-seed points like the rest.
    out = run(["-n", "-p", "-R", "budget", "budget"])
    assert out.returncode == 0, out.stderr
    text = out.stdout + out.stderr
    # the cpu preset's study walks its from-scratch learner's settings (config budget: reference)
    assert "--chosen head_on_from_scratch " in text
    for seed in (0, 1, 2):
        assert f"--run head_on_from_scratch=results/cpu/train/head_on_from_scratch/seed{seed}/curve.csv" in text
    assert "--run head_on_kitchen_living=results/cpu/train/head_on_kitchen_living/seed0/curve.csv" in text
    assert "head_on_kitchen_living/seed1/" not in text
    smoke = run(["-n", "-p", "budget", "--config", "preset=smoke"])
    assert smoke.returncode == 0, smoke.stderr
    assert "--chosen head_on " in smoke.stdout + smoke.stderr


def test_a_smoke_screens_cost_line_is_minutes_at_the_capped_steps():
    """Issue 73 item 3: head_on_25px pins 300,000 env steps; a smoke screen of it plans the capped config's steps
    (the cost line and the training read one config, resolve_variant's) and costs minutes."""
    from egosearch.variants import resolve_variant

    steps = resolve_variant("head_on_25px", "smoke").config.total_env_steps
    out = run(["-n", "screen", "--config", "variant=head_on_25px", "preset=smoke", "screen_seeds=1"])
    assert out.returncode == 0, out.stderr
    line = next(x for x in out.stderr.splitlines() if x.startswith("screen of head_on_25px against head_on: "))
    assert f"3 training(s) (2 of them head_on's, the reference's) of {steps} env steps, about " in line, line
    minutes = float(re.search(r"about ([0-9.]+) min on \d+ core", line).group(1))
    assert steps == 300 and 0 < minutes < 30, line


def test_dry_run_of_behaviour_traces_every_pair_outside_all():
    out = run(["-n", "-p", "behaviour", "searches", "--config", "preset=smoke"])
    assert out.returncode == 0, out.stderr
    text = out.stdout + out.stderr
    for variant in ("head_on", "head_off", "frontier", "frontier_head_off"):
        for home in ("kitchen_living", "bedroom_bath"):
            assert f"traces/{variant}/seed0/{home}/everywhere/h1.65.npz" in text, (variant, home)
    assert "--traces results/smoke/traces/head_on/seed0/kitchen_living/everywhere/h1.65.npz" in text
    # the classical searchers are traced by their own rule, with no actor
    assert ("egosearch evaluate --force --policy frontier_head_off --scenarios "
            "results/smoke/scenarios/bedroom_bath/everywhere/h1.65.csv --seed 0 --out "
            "results/smoke/traces/frontier_head_off/seed0/bedroom_bath/everywhere/h1.65.csv --traces") in text
    assert "--pairs head_on:head_off frontier:frontier_head_off --out-prefix paper_figs/smoke/behaviour" in text
    assert "searches/frontier_" not in text
    assert "searches/gaze_kitchen_living_everywhere_h1.65.png" in text
    assert "trace" not in run(["-n", "all", "--quiet", "rules", "--config", "preset=smoke"]).stdout.split()


def test_lint_is_clean():
    out = run(["--lint"])
    assert out.returncode == 0, out.stdout + out.stderr
    assert "Congratulations" in out.stdout + out.stderr


@pytest.mark.parametrize("override, key", [
    ("preset=fast", "preset"),
    ("heights=[7.0]", "heights"),
    ("placements=[under_the_sofa]", "placements"),
])
def test_schema_rejects_bad_config_before_any_job(override, key):
    out = run(["-n", "all", "--config", override])
    assert out.returncode != 0
    assert key in out.stdout + out.stderr


def test_unknown_variant_is_named_before_any_job():
    out = run(["-n", "all", "--config", "variants=[head_on,hed_off]"])
    assert out.returncode != 0
    assert "hed_off" in out.stdout + out.stderr and "allowed" in out.stdout + out.stderr


@pytest.mark.slow  # the whole smoke DAG, about 4 minutes on 2 cores: CI runs it (.ci/run)
def test_smoke_table1_end_to_end(checkout):
    # the reference's success by path length reads the same evaluations: one more job. The timeout
    # only stops a hang: the run is 75 one-process jobs, and it took over 15 minutes beside three
    # training jobs.
    out = run(["table1", "paper_figs/smoke/pathlength_head_on.md", "--config", "preset=smoke"],
              cwd=checkout, timeout=2400)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    by_length = pd.read_csv(checkout / "results/smoke/pathlength/head_on.csv")
    pooled = by_length[(by_length["searcher"] == "head_on") & (by_length["height"] == "all")]
    # 2 homes x 6 cells x 4 scenarios, each in one bin of each binning
    assert pooled.groupby("by")["n_scenarios"].sum().to_dict() == {"detour": 48, "length": 48}
    assert {"random", "oracle"} <= set(by_length["searcher"])
    assert (checkout / "paper_figs/smoke/pathlength_head_on.png").stat().st_size > 10_000
    md = (checkout / "paper_figs/smoke/table1.md").read_text()
    assert "| 1.05m | paper | 0.92 | 0.75 |" in md and "| 0.45m | ours (head_on) | " in md
    for home in ("kitchen_living", "bedroom_bath"):  # both of the paper's homes
        evals = sorted((checkout / f"results/smoke/eval/head_on/seed0/{home}").rglob("h*.csv"))
        assert len(evals) == 6
        # The bounds ran on the same scenario sets, and Table 1 shows them: the oracle finds targets.
        for bound in ("random", "oracle"):
            assert len(list((checkout / f"results/smoke/eval/{bound}/seed0/{home}").rglob("h*.csv"))) == 6
    table = pd.read_csv(checkout / "paper_figs/smoke/table1.csv")
    assert sorted(set(table["home"])) == ["bedroom_bath", "both", "kitchen_living"]
    per_home, both = table[table["home"] != "both"], table[table["home"] == "both"]
    assert (per_home["oracle_n_episodes"] == 4).all() and (both["oracle_n_episodes"] == 8).all()
    assert table["oracle_success_rate"].mean() > 0.5
    assert md.index("both homes pooled") < md.index("Table 1 in bedroom_bath alone")
    assert "not run" not in md
    # The scenario sets are fixed: the same rows on a second generation.
    scen = checkout / "results/smoke/scenarios/kitchen_living/everywhere/h1.65.csv"
    again = subprocess.run(["egosearch", "scenarios", "--placement", "everywhere", "--height", "1.65", "--n", "4",
                            "--seed", "2021", "--out", str(checkout / "again.csv")], capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    assert scen.read_text() == (checkout / "again.csv").read_text()


def test_smoke_fig7_with_the_oracle_planner_end_to_end(checkout):
    out = run(["--cores", "2", "fig7_oracle", "--config", "preset=smoke"], cwd=checkout, timeout=900)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    assert not (checkout / "results/smoke/train").exists()   # the oracle planner needs no training
    fig = pd.read_csv(checkout / "paper_figs/smoke/fig7_oracle.csv")
    assert set(fig["method"]) == {"ours", "one_step_short", "one_step_long", "noisy_search"}
    ours = fig[fig["method"] == "ours"].set_index("M")
    assert sorted(ours.index) == [5, 20] and (ours["n_episodes"] == 2).all()
    # The oracle finds the target through Algorithm 1; fewer steps per plan means more plans.
    assert ours["success_rate"].min() > 0
    assert ours.loc[5, "attempts"] > ours.loc[20, "attempts"]
    assert (checkout / "paper_figs/smoke/fig7_oracle.png").stat().st_size > 10_000


def test_cluster_generic_executor_runs_the_same_dag(checkout):
    submit = checkout / "tests/data/local_submit.sh"
    out = run(["--executor", "cluster-generic", "--cluster-generic-submit-cmd", f"bash {submit}", "--jobs", "2",
               "--latency-wait", "30", "table2", "table2_paper", "--config", "preset=smoke"], cwd=checkout)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    table = (checkout / "paper_figs/table2.md").read_text()
    assert "| Batch-size | 32 |" in table and "| Replay buffer | 100000 |" in table
    assert "0.75M" in table


def test_config_file_is_valid_yaml_with_all_presets():
    config = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())
    assert set(config["presets"]) == {"smoke", "cpu", "paper"}
    assert config["preset"] == "cpu"


def test_a_report_with_stored_outputs_and_missing_inputs_is_named():
    from egosearch.workflow.check import reports_missing_inputs

    stored = {"fig6.png", "fig6.csv", "a/curve.csv"}
    rules = [("fig6", ["fig6.png", "fig6.csv"], ["a/curve.csv", "new/curve.csv"]),
             ("table1", ["table1.csv"], ["new/curve.csv"]),  # not made yet: Snakemake makes it
             ("budget", ["fig6.csv"], ["a/curve.csv"])]  # nothing missing
    lines = reports_missing_inputs(rules, exists=stored.__contains__)
    assert lines == ["fig6: its outputs are stored but 1 of its inputs are not (e.g. new/curve.csv); Snakemake "
                     "will not make them for it: add `-R fig6` to make them and redo fig6"]


def test_a_variant_added_to_the_config_is_named_with_the_command_that_makes_it():
    untrained = [p.stem for p in sorted((REPO / "ablations").glob("head_on_*.yaml"))
                 if not (REPO / "results" / "cpu" / "train" / p.stem).exists()]
    if not untrained or not (REPO / "paper_figs" / "cpu" / "fig6.csv").exists():
        pytest.skip("needs the stored cpu Figure 6 and an ablation without cpu results")
    result = run(["-n", "fig6", "--config", f"variants=[head_on,head_off,{untrained[0]}]"])
    assert result.returncode == 0, result.stderr
    assert "fig6: its outputs are stored but 3 of its inputs are not" in result.stderr + result.stdout
    assert "add `-R fig6`" in result.stderr + result.stdout


def test_a_stored_comparison_gives_no_missing_input_line():
    if not (REPO / "results" / "cpu" / "compare" / "head_off_vs_head_on.csv").exists():
        pytest.skip("needs the stored cpu comparison head_off vs head_on")
    homes = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())["homes"]
    if not all((REPO / "results/cpu/eval/head_off/seed0" / home).exists() for home in homes):
        pytest.skip("the stored cpu run predates the config's homes: its comparison lacks inputs (README: Status)")
    result = run(["-n", "compare", "--config", "variant=head_off"])
    assert result.returncode == 0, result.stderr
    # other rules' lines (a budget setting not trained yet) are not this test's business
    assert "compare: its outputs are stored" not in result.stderr + result.stdout


def test_a_screen_trains_screen_seeds_against_the_references_spread_seeds():
    """`snakemake screen --config variant=NAME`: the lever screen as one command, on screen_seeds seeds from
    screen_seed, read against every spread seed of the reference (the smoke preset's: 0 and 1)."""
    out = run(["-n", "screen", "--config", "preset=smoke", "variant=head_off", "screen_seed=1", "screen_seeds=2"])
    assert out.returncode == 0, out.stderr
    text = out.stdout + out.stderr
    assert "results/smoke/compare/screen_head_off_seeds1-2_vs_head_on.csv" in text
    assert "results/smoke/compare/screen_head_off_seeds1-2_vs_head_on_aggregate.csv" in text
    assert "eval/head_off/seed1/" in text and "eval/head_off/seed2/" in text and "eval/head_off/seed0/" not in text
    assert "eval/head_on/seed0/" in text and "eval/head_on/seed1/" in text and "eval/head_on/seed2/" not in text
    one = run(["-n", "screen", "--config", "preset=smoke", "variant=head_off", "screen_seeds=1"])
    assert "results/smoke/compare/screen_head_off_seed0_vs_head_on.csv" in one.stdout + one.stderr
    missing = run(["-n", "screen", "--config", "preset=smoke"])
    assert missing.returncode != 0 and "screen needs a variant" in missing.stdout + missing.stderr


def job_stats(text: str) -> dict[str, int]:
    """Snakemake's "Job stats" table of a dry run's output, as {rule: count, "total": n}."""
    lines = text.split("Job stats:\n", 1)[1].splitlines()[2:]
    stats = {}
    for line in lines:
        if not line.strip():
            break
        rule, count = line.split()
        stats[rule] = int(count)
    return stats


def cost_line(text: str, opening: str) -> tuple[str, dict[str, int]]:
    """The cost line that opens with ``opening``, and the counts it gives per rule (as job_stats reads them)."""
    [line] = [x for x in text.splitlines() if x.startswith(opening)]
    counted = re.match(r".*?: (\d+) jobs? to run \(([^)]*)\)", line)
    counts = {rule: int(n) for n, rule in (part.split(" ") for part in counted.group(2).split(", "))}
    return line, {**counts, "total": int(counted.group(1))}


def test_the_cost_line_counts_every_job_of_the_plan():
    """Issue 57: the line a dry run prints above its plan counts the plan's jobs as Snakemake's own job stats
    count them, the reference's trainings and evaluations included (a comparison against a reference whose
    seeds are not all stored trains them too), and a screen's; once, on the preset's cores."""
    config = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())
    seeds = config["presets"]["cpu"]["seeds"]
    candidates = [v for v in ("head_on_ppo", "head_on_recurrent", "head_on_geodesic")
                  if not all((REPO / f"results/cpu/train/{v}/seed{s}/done.json").exists() for s in seeds)]
    reference = candidates[0]
    missing = sum(not (REPO / f"results/cpu/train/{reference}/seed{s}/done.json").exists() for s in seeds)
    out = run(["-n", "compare", "--config", "variant=head_off", f"reference_variant={reference}"])
    assert out.returncode == 0, out.stderr[-3000:]
    text = out.stdout + out.stderr
    line, counted = cost_line(out.stderr, f"compare of head_off against {reference}: ")
    assert counted == job_stats(text) and counted["train"] == missing >= 1, line
    assert f"{missing} training(s) ({missing} of them {reference}'s, the reference's)" in line
    assert f"{counted['evaluate']} evaluations ({counted['evaluate']} of them {reference}'s)" in line
    assert line.endswith(f" on {PRESET_CORES} core(s)") and out.stderr.splitlines().count(line) == 1

    out = run(["-n", "screen", "--config", "variant=head_off"])
    assert out.returncode == 0, out.stderr[-3000:]
    text = out.stdout + out.stderr
    line, counted = cost_line(out.stderr, "screen of head_off against head_on: ")
    assert counted == job_stats(text) and counted["screen"] == 1 and counted["train"] >= 1, line
    # and the power of that screen, beside its cost
    assert any(f"a screen of {config['screen_seeds']} seed(s) against head_on" in x or x.startswith("(no power line")
               for x in out.stderr.splitlines())


def test_a_dry_run_without_a_stored_run_says_why_there_is_no_estimate(checkout):
    for target, what in (("screen", "the screen's cost"), ("all", "the run's time")):
        out = run(["-n", target, "--config", "preset=smoke", "variant=head_off"], cwd=checkout)
        assert out.returncode == 0, out.stderr
        assert (f"(no estimate of {what}: the smoke preset has no stored run whose job times an estimate scales "
                "(results/smoke/provenance.json is not there); a smoke run is plumbing only, minutes long)"
                in out.stderr.splitlines()), out.stderr
        assert "Errno" not in out.stderr


def test_the_cpu_profile_reads_the_claims_on_its_from_scratch_pair_too():
    """Its pair is a modular searcher: the claims are read both ways (the pair that learned every body step is
    stored); the other presets read the top level's pairs."""
    from egosearch.report.workflow_jobs import claims_pairs

    config = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())
    assert claims_pairs({**config, "preset": "cpu"}) == [
        ["head_on", "head_off"], ["head_on_from_scratch", "head_off_from_scratch"],
        ["head_on_modular", "head_off_modular"], ["frontier", "frontier_head_off"]]
    assert claims_pairs({**config, "preset": "smoke"}) == config["claims_pairs"] == [
        ["head_on", "head_off"], ["frontier", "frontier_head_off"]]


def recorded_job(rule: str, preset: str, **wildcards) -> dict:
    """The provenance row of one job of ``rule``, keyed as the record keys it (egosearch.report.provenance):
    the rule's ``benchmark:`` path, as its .smk file writes it, under results/<preset>/benchmarks/, split
    into its first folder (the recorded rule) and the rest (the job)."""
    text = "\n".join(path.read_text() for path in sorted((REPO / "egosearch/workflow/rules").glob("*.smk")))
    [body] = re.findall(rf"^rule {rule}:\n(.*?)(?=^\S|\Z)", text, re.MULTILINE | re.DOTALL)
    [benchmark] = re.findall(r'benchmark:\s*\n\s*"([^"]+)\.tsv"', body)
    key = benchmark.format(preset=preset, **wildcards).removeprefix(f"results/{preset}/benchmarks/")
    first, rest = key.split("/", 1)
    return {"rule": first, "job": rest, "wall_s": 1.0}


def test_a_policys_job_is_of_all_only_for_a_variant_of_all_at_one_of_the_presets_seeds():
    """The study a recorded job is counted in (README's provenance, docs/gpu.md): the starts' evaluations of
    `all`'s pair (what learning adds) are of `all`, a lever's start is not; the reference's spread seeds
    (`snakemake seed_spread`, beyond the preset's seeds) are outside `all` whichever rule ran them."""
    from egosearch.report.workflow_jobs import job_study, preset_seeds, variants_of_all

    config = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())
    assert preset_seeds(config, "cpu") == [0, 1, 2] and preset_seeds(config, "smoke") == [0]
    assert preset_seeds({**config, "preset": "smoke"}) == [0]
    lever = "head_on_contact_signal"  # a screened lever: neither of `all` nor of the generalisation study
    assert (REPO / "ablations" / f"{lever}.yaml").is_file() and lever not in variants_of_all(config)
    assert {"head_on", "head_off"} <= set(variants_of_all(config))
    cell = {"layout": "kitchen_living", "placement": "everywhere", "height": "1.05"}

    def study(rule, variant, seed, preset="cpu"):
        job = recorded_job(rule, preset, variant=variant, seed=seed, **cell)
        return job_study(job, config, preset)

    start = recorded_job("evaluate_start", "cpu", variant="head_on", seed=0, **cell)
    assert start == {"rule": "eval_start", "job": "head_on/seed0/kitchen_living/everywhere/h1.05", "wall_s": 1.0}
    assert study("evaluate_start", "head_on", 0) == "all"
    assert study("evaluate_start", "head_off", 2) == "all"
    assert study("evaluate_start", lever, 0) == "other"
    assert study("evaluate_start", "head_on", 3) == "other"
    for rule in ("train", "evaluate"):
        assert study(rule, "head_on", 1) == "all"
        assert study(rule, "head_on", 3) == "other" and study(rule, "head_on", 4) == "other"
        assert study(rule, lever, 0) == "other"
        assert study(rule, "head_on_generated_homes", 0) == "generalise"
        # the pair before the redo is read in the generalisation table
        assert study(rule, "head_on_tuned_teacher_geodesic_contact", 0) == "generalise"
        # the smoke preset's `all` trains seed 0 alone
        assert study(rule, "head_on", 0, "smoke") == "all" and study(rule, "head_on", 1, "smoke") == "other"
    # the preset is the job's, not the config's: a cpu record read with a smoke config
    job = recorded_job("train", "cpu", variant="head_on", seed=1)
    assert job_study(job, {**config, "preset": "smoke"}, "cpu") == "all"
    assert job_study(job, {**config, "preset": "smoke"}) == "other"
    # a record of a preset the config does not list: its seeds are unknown, so every seed counts
    with pytest.raises(ValueError, match="preset 'p' is not in the config"):
        preset_seeds(config, "p")
    assert job_study(recorded_job("train", "p", variant="head_on", seed=3), config, "p") == "all"


def test_the_decisions_floor_compares_the_modular_pair_with_the_same_walk_on_random_decisions():
    """At the cpu preset (a modular searcher): head_on against modular_random, head_off against
    modular_random_head_off, every seed against the floor's one, on the stored sets; nothing at a preset
    whose pair acts at every body step."""
    out = run(["-n", "-p", "decisions_floor", "-R", "decisions_floor_compare"])
    assert out.returncode == 0, out.stderr
    text = out.stdout + out.stderr
    for variant, floor in (("head_on_modular", "modular_random"), ("head_off_modular", "modular_random_head_off")):
        assert f"--out results/cpu/compare/{variant}_vs_{floor}.csv" in text
        assert f"results/cpu/eval/{floor}/seed0/bedroom_bath/everywhere/h1.65.csv" in text
        assert f"results/cpu/eval/{variant}/seed2/kitchen_living/no_low_cabinets/h0.45.csv" in text
    assert f"eval/{floor}/seed1/" not in text
    smoke = run(["-n", "-p", "decisions_floor", "--config", "preset=smoke"])
    assert smoke.returncode == 0 and "report compare" not in smoke.stdout + smoke.stderr


def test_learning_adds_compares_the_pair_with_its_own_start_on_the_same_sets(checkout):
    """`learning_adds`: every seed's start (actor_start.pt, beside the actor.pt the train rule makes) on every
    Table 1 cell under eval_start/, and each variant of the pair against it, seed by seed."""
    out = run(["-n", "-p", "learning_adds", "--config", "preset=smoke"], cwd=checkout)
    assert out.returncode == 0, out.stderr
    text = out.stdout + out.stderr
    for variant in ("head_on", "head_off"):
        assert (f"--weights results/smoke/train/{variant}/seed0/actor_start.pt --scenarios "
                f"results/smoke/scenarios/kitchen_living/everywhere/h1.05.csv --seed 0 --out "
                f"results/smoke/eval_start/{variant}/seed0/kitchen_living/everywhere/h1.05.csv") in text
        compare = next(line for line in text.splitlines()
                       if f"--out results/smoke/compare/{variant}_vs_its_start.csv" in line)
        reference, candidate = compare.split("--reference ")[1].split(" --candidate ")
        assert f"results/smoke/eval_start/{variant}/seed0/bedroom_bath/no_low_cabinets/h0.45.csv" in reference
        assert "/eval/" not in reference and "/eval_start/" not in candidate.split(" --out ")[0]
        assert f"results/smoke/eval/{variant}/seed0/bedroom_bath/no_low_cabinets/h0.45.csv" in candidate
