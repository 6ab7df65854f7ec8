"""`egosearch estimate all`: the DAG's schedule from the stored record, scaled to a machine's rate."""

import json
import os
from pathlib import Path

import pytest

from egosearch.cli import main
from egosearch.cost.estimate import estimate_all

REPO = Path(__file__).resolve().parent.parent
RECORD = REPO / "results" / "cpu" / "provenance.json"


@pytest.mark.skipif(not RECORD.exists(), reason="no stored cpu run")
def test_the_estimate_simulates_the_schedule_and_scales_trainings_to_the_machine(monkeypatch):
    monkeypatch.chdir(REPO)
    from egosearch.cost.rates import steps_of_preset, stored_training_rates

    record = json.loads(RECORD.read_text())
    # rates in the preset's own unit (decisions for a modular searcher), about the recorded ones
    base = min(stored_training_rates(record, RECORD.parent, steps_of_preset("cpu")).values())
    slow = estimate_all(record, RECORD.parent, 2, "cpu", rate=base)
    fast = estimate_all(record, RECORD.parent, 2, "cpu", rate=2 * base)
    # waiting and imperfect packing: the schedule is never shorter than CPU time / cores
    assert slow["hours_as_recorded"] >= slow["hours_cpu_over_cores"]
    # each training at the slowest rate costs at least its own CPU time, so its cores are never less busy
    assert slow["hours_at_slowest_recorded_rate"] >= slow["hours_cpu_over_cores"]
    assert fast["hours_here"] < slow["hours_here"]
    # the trainings, scaled, still dominate: the slowest jobs are trainings
    assert all(name.startswith("train/") for name, _ in fast["slowest_jobs_here"])
    one_core = estimate_all(record, RECORD.parent, 1, "cpu", rate=2 * base)
    assert one_core["hours_here"] > fast["hours_here"]


def test_bad_estimate_inputs_are_one_line(capsys):
    assert main(["estimate", "all", "--cores", "0"]) == 2
    assert main(["estimate", "all", "--rate", "-5"]) == 2
    assert main(["estimate", "all", "--rate", "5", "--from-bench"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 3 and "--cores=0" in err and "--rate=-5" in err and "give one" in err


def test_a_training_says_at_its_start_how_long_it_takes_here(tmp_path, monkeypatch):
    """From this machine's cached calibration; without one it names the command that makes one."""
    import egosearch.cost.estimate as estimate
    from egosearch.core.machine import cpu_model, cpu_vector_unit
    from egosearch.cost import calibration

    monkeypatch.chdir(tmp_path)  # no stored record here: a training is taken at the calibrated rate
    monkeypatch.setattr(calibration, "CALIBRATION_CACHE", tmp_path / "rate.json")
    assert "egosearch estimate all" in estimate.training_time_line(200_000, "cpu")
    here = estimate.machine_key({"cpu": cpu_model(), "vector_unit": cpu_vector_unit(), "cores": os.cpu_count()})
    (tmp_path / "rate.json").write_text(json.dumps({"machine": here, "rate": 100.0, "steps": "body steps"}))
    assert estimate.training_time_line(180_000, "cpu").startswith("estimate: about 0.5 h of CPU time")
    (tmp_path / "rate.json").write_text(json.dumps({"machine": "another machine", "rate": 100.0,
                                                    "steps": "decisions"}))
    assert "no calibration" in estimate.training_time_line(180_000, "cpu")
    # a calibration made while the preset was a modular searcher timed its decisions, not body steps
    (tmp_path / "rate.json").write_text(json.dumps({"machine": here, "rate": 100.0, "steps": "decisions"}))
    assert "no calibration" in estimate.training_time_line(180_000, "cpu")
    assert estimate.training_time_line(180_000, "smoke") is None


def test_a_training_that_learned_from_the_teacher_is_rated_on_its_rl_phase(tmp_path):
    """Its CPU time also paid for the teacher's episodes and the cloning: counted whole, 4,000 env steps in 600
    CPU-s would put the benchmark's pairing with a training at 1/20 of itself. Hand-worked: 60,000 env steps in
    1,000 CPU-s, of which 250 went to the demonstrations and 150 to the cloning: 60,000 / 600 = 100. A run that
    recorded no cloning time is left out; one with demonstrations in replay and no cloning pays only them. A
    modular searcher's run is left out too: its env steps are decisions."""
    import json

    from egosearch.cost.rates import stored_training_rates

    results = tmp_path / "results" / "cpu"
    jobs = []
    for job, steps, cpu_s, demos, done in (
            ("scratch/seed0", 200_000, 2000.0, 0, None),
            ("cloned/seed0", 4000, 600.0, 1500, {"demonstrations": {"cpu_s": 355.0}, "config": {"bc_updates": 12000}}),
            ("finetuned/seed0", 60_000, 1000.0, 1500, {"demonstrations": {"cpu_s": 250.0},
                                                       "imitation": {"cpu_s": 150.0}, "config": {"bc_updates": 9}}),
            ("replayed/seed0", 30_000, 550.0, 1500, {"demonstrations": {"cpu_s": 250.0}, "config": {"bc_updates": 0}}),
            ("modular/seed0", 30_000, 2400.0, 0, None)):
        run = results / "train" / job
        run.mkdir(parents=True)
        (run / "curve.csv").write_text(f"env_steps,success_rate\n0,0.1\n{steps},0.5\n")
        env_id = "EgoSearchModular-v0" if job.startswith("modular") else "EgoSearchMemory-v0"
        (run / "config.json").write_text(json.dumps({"env_id": env_id, "config": {"demo_episodes": demos}}))
        if done is not None:
            (run / "done.json").write_text(json.dumps(done))
        jobs.append({"rule": "train", "job": job, "wall_s": cpu_s, "cpu_s": cpu_s})
    assert stored_training_rates({"jobs": jobs}, results) == {"scratch/seed0": 100.0, "finetuned/seed0": 100.0,
                                                              "replayed/seed0": 100.0}
    # a modular searcher's rate counts decisions, apart: 30,000 / 2,400 CPU-s = 12.5, i.e. 0.08 CPU-s each
    from egosearch.cost.rates import stored_cpu_s_per_step
    from egosearch.rl.config import DECISIONS

    assert stored_training_rates({"jobs": jobs}, results, DECISIONS) == {"modular/seed0": 12.5}
    assert stored_cpu_s_per_step({"jobs": jobs}, results, DECISIONS) == pytest.approx(0.08)
    assert stored_cpu_s_per_step({"jobs": jobs[:1]}, results, DECISIONS) is None


def test_a_cloning_that_was_not_timed_is_priced_at_the_stored_runs_cost_per_cloning_step(tmp_path):
    """Hand-worked: run A recorded its cloning, 120 CPU-s for 12,000 steps (0.01 s each), and spent 300 on
    demonstrations: 60,000 env steps in 1,020 CPU-s make 60,000 / 600 = 100 per CPU-s. Run B cloned 6,000
    steps before trainings timed it: 60 CPU-s at A's price, plus its 200 s of demonstrations, leave 400 of its
    660 CPU-s to 40,000 env steps: 100 per CPU-s."""
    import json

    from egosearch.cost.rates import cpu_s_outside_rl, stored_training_rates

    results = tmp_path / "results" / "cpu"
    jobs = []
    for job, steps, cpu_s, done in (
            ("a/seed0", 60_000, 1020.0, {"demonstrations": {"cpu_s": 300.0},
                                         "imitation": {"cpu_s": 120.0, "bc_updates": 12000},
                                         "config": {"bc_updates": 12000}}),
            ("b/seed0", 40_000, 660.0, {"demonstrations": {"cpu_s": 200.0}, "config": {"bc_updates": 6000}})):
        run = results / "train" / job
        run.mkdir(parents=True)
        (run / "curve.csv").write_text(f"env_steps,success_rate\n0,0.1\n{steps},0.5\n")
        (run / "config.json").write_text(json.dumps({"env_id": "EgoSearch-v0", "config": {"demo_episodes": 1500}}))
        (run / "done.json").write_text(json.dumps(done))
        jobs.append({"rule": "train", "job": job, "wall_s": cpu_s, "cpu_s": cpu_s})
    assert cpu_s_outside_rl(results / "train" / "b/seed0") == pytest.approx(260.0)
    assert stored_training_rates({"jobs": jobs}, results) == pytest.approx({"a/seed0": 100.0, "b/seed0": 100.0})
    # without a run that timed its cloning, B has no price: left out, as before
    (results / "train" / "a/seed0" / "done.json").unlink()
    assert cpu_s_outside_rl(results / "train" / "b/seed0") is None


def test_a_training_that_learns_from_the_teacher_adds_its_imitation_phase(tmp_path, monkeypatch):
    """Hand-worked: 100 demonstration and 20 DAgger episodes at 0.25 CPU-s each and 2 x 500 cloning steps at 50
    updates per second on the benchmark's machine (30 + 20 s), on a machine calibrated at half its rate: 100 s."""
    import egosearch.cost.estimate as estimate
    from egosearch.core.machine import cpu_model, cpu_vector_unit
    from egosearch.cost import calibration, rates
    from egosearch.rl.config import load_config

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(calibration, "CALIBRATION_CACHE", tmp_path / "rate.json")
    here = estimate.machine_key({"cpu": cpu_model(), "vector_unit": cpu_vector_unit(), "cores": os.cpu_count()})
    (tmp_path / "rate.json").write_text(json.dumps({"machine": here, "rate": 50.0}))
    results = tmp_path / "results" / "cpu"
    (results / "bench").mkdir(parents=True)
    bench = {"result": {"updates_per_s_cpu_profile": 50.0, "env_steps_per_core_s_cpu_profile": 100.0}}
    (results / "bench" / "learner.json").write_text(json.dumps(bench))
    cfg = load_config("cpu", {"modular_searcher": False, "demo_episodes": 100, "bc_updates": 500,
                              "dagger_rounds": 1, "dagger_episodes": 20})
    # the calibration times the preset's body steps, as this training's: its RL phase at the calibrated rate
    line = estimate.training_time_line(200_000, "cpu", cfg)
    assert "calibrated at 50 body steps per CPU-second" in line and "teacher's 100 episodes" in line
    run = results / "train" / "cloned" / "seed0"
    run.mkdir(parents=True)
    (run / "done.json").write_text(json.dumps({"demonstrations": {"episodes": 1500, "cpu_s": 375.0}}))
    # 100 + 20 episodes x 0.25 s = 30 s, 1000 cloning steps / 50 per s = 20 s; x 100 / 50 = 100 s
    assert rates.teacher_cost_s(cfg, results, bench, 50.0) == pytest.approx(100.0)


@pytest.mark.skipif(not RECORD.exists(), reason="no stored cpu run")
def test_estimate_all_prints_its_answer_naming_the_cpu_and_a_busy_machine(tmp_path, monkeypatch, capsys):
    """The calibration's own lines (its evaluations, its config) are held back: stdout is the answer, whose
    first figure names the CPU it was calibrated on; other processes' 1.5 cores meanwhile get a line."""
    import types

    import egosearch.cost.estimate as estimate
    import egosearch.rl.bench_learner
    from egosearch.cost import calibration
    from egosearch.workflow.dag import DagJob

    def short_training(preset, env_steps):
        print("eval @ 0: success nan  return nan  spl nan")  # what a real calibration prints
        return {"env_steps_per_core_s": 40.0}

    monkeypatch.chdir(REPO)
    monkeypatch.setattr(calibration, "CALIBRATION_CACHE", tmp_path / "rate.json")
    monkeypatch.setattr(egosearch.rl.bench_learner, "training_throughput", short_training)
    monkeypatch.setattr(egosearch.rl.bench_learner, "cpu_preset_run_steps", lambda: 10)
    monkeypatch.setattr(estimate, "dag_jobs", lambda target, cores, config: [
        DagJob(id="train/head_on/seed0", rule="train", job="head_on/seed0", record_rule="train", threads=1, deps=(),
               order=1)])
    # 60 s of calibration in which the machine's CPU time grew by 100 s, 10 of them its own: 1.5 other cores
    monkeypatch.setattr(calibration, "time", types.SimpleNamespace(perf_counter=iter([0.0, 60.0]).__next__))
    monkeypatch.setattr(calibration, "cpu_seconds_all", iter([1000.0, 1100.0]).__next__)
    monkeypatch.setattr(calibration, "own_cpu_seconds", iter([5.0, 15.0]).__next__)
    assert main(["estimate", "all"]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert "nan" not in out and lines[0].startswith("snakemake --cores 2 all from a fresh clone, cpu preset")
    here = estimate.machine_key(calibration.this_machine())
    assert lines[1].startswith(f"  on this machine ({here}): about ") and "40 body steps per CPU-second" in lines[1]
    assert ("  the machine was busy while it calibrated: other processes used 1.5 cores meanwhile, so the rate here "
            "may be low and the estimate long (calibrate again when it is idle)") in lines
    assert err.startswith("calibrating: ")
    assert json.loads((tmp_path / "rate.json").read_text())["other_load_cores"] == 1.5


def test_a_comparisons_cost_adds_the_teachers_episodes_of_a_variant_that_learns_from_them(tmp_path, monkeypatch,
                                                                                          capsys):
    """A variant with demo_episodes runs the classical searcher's episodes and clones them before its RL phase,
    whose rate alone the stored trainings give: the cost line adds them, or says it cannot price them."""
    import egosearch.cost.estimate as estimate
    from egosearch.cost import calibration
    from egosearch.variants import resolve_variant

    variant = "head_on_imitation_finetune"
    config = resolve_variant(variant, "cpu").config
    assert config.demo_episodes and config.env_step_unit == "body steps"
    results = tmp_path / "results" / "cpu"
    (results / "bench").mkdir(parents=True)
    (results / "provenance.json").write_text(json.dumps({"preset": "cpu", "jobs": [
        {"rule": "eval", "job": "x/seed0/kitchen_living/everywhere/h1.05", "wall_s": 40.0}]}))
    (results / "bench" / "learner.json").write_text(json.dumps({"result": {
        "env_steps_per_core_s_cpu_profile": 100.0, "cpu_profile_steps": "body steps"}}))  # 0.01 CPU-s a step
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(calibration, "CALIBRATION_CACHE", tmp_path / "rate.json")
    monkeypatch.setattr(estimate, "stored_cpu_s_per_step", lambda record, results, kind: 0.01)
    rl_phase = config.total_env_steps * 0.01
    unpriced = "plus the teacher's {} episodes and the cloning (no stored measurement prices them)"
    for teacher_s, said in ((1800.0, "of which about 0.5 h the teacher's"), (None, unpriced)):
        monkeypatch.setattr(estimate, "teacher_cost_s", lambda config, results, bench, rate, s=teacher_s: s)
        estimate.print_plan_cost(f"screen of {variant} against head_on", [training_job(variant)], "cpu", 1,
                                 "head_on")
        line = capsys.readouterr().err
        each = (rl_phase + (teacher_s or 0.0)) / 3600
        assert f"1 training(s) of {config.total_env_steps} env steps, about {each:.1f} h each" in line, line
        assert said.format(config.demo_episodes) in line


def training_job(variant: str, seed: int = 0, deps=()):
    """A plan's training job, as egosearch.workflow.dag.plan_jobs reads it from a DAG."""
    from egosearch.workflow.dag import DagJob

    return DagJob(id=f"train/{variant}/seed{seed}", rule="train", job=f"{variant}/seed{seed}", record_rule="train",
                  threads=1, deps=tuple(deps), order=seed, wildcards={"preset": "cpu", "variant": variant,
                                                                      "seed": str(seed)})


def evaluation_job(variant: str, seed: int, cell: str, order: int):
    from egosearch.workflow.dag import DagJob

    return DagJob(id=f"eval/{variant}/seed{seed}/{cell}", rule="evaluate", job=f"{variant}/seed{seed}/{cell}",
                  record_rule="eval", threads=1, deps=(f"train/{variant}/seed{seed}",), order=order,
                  wildcards={"preset": "cpu", "variant": variant, "seed": str(seed)})



def _calibrated_at_100_steps_a_second(tmp_path, monkeypatch) -> None:
    """Work in ``tmp_path`` with this machine's calibration cached there at 100 body steps a second."""
    import egosearch.cost.estimate as estimate
    from egosearch.cost import calibration

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(calibration, "CALIBRATION_CACHE", tmp_path / "rate.json")
    (tmp_path / "rate.json").write_text(json.dumps({"machine": estimate.machine_key(calibration.this_machine()),
                                                    "rate": 100.0, "steps": "body steps"}))

def test_the_cost_line_counts_every_job_of_the_plan(tmp_path, monkeypatch, capsys):
    """Issue 57: the line counts the plan's jobs by rule, as Snakemake's job stats do, the reference's
    trainings and evaluations among them, each training at its own variant's steps, and lays them out."""
    import egosearch.cost.estimate as estimate
    from egosearch.workflow.dag import DagJob

    _calibrated_at_100_steps_a_second(tmp_path, monkeypatch)
    results = tmp_path / "results" / "cpu"
    (results / "bench").mkdir(parents=True)
    (results / "provenance.json").write_text(json.dumps({"preset": "cpu", "jobs": [
        {"rule": "eval", "job": "x/seed0/kitchen_living/everywhere/h1.05", "wall_s": 40.0},
        {"rule": "eval", "job": "x/seed0/kitchen_living/everywhere/h1.65", "wall_s": 60.0}]}))
    monkeypatch.setattr(estimate, "teacher_cost_s", lambda config, results, bench, rate: 360.0)
    plan = [training_job("head_off", 3), training_job("head_on", 5), evaluation_job("head_off", 3, "c1", 2),
            evaluation_job("head_on", 5, "c1", 3), evaluation_job("head_on", 5, "c2", 4),
            DagJob(id="screen", rule="screen", job=None, record_rule=None, threads=1, order=5,
                   deps=("eval/head_off/seed3/c1", "eval/head_on/seed5/c1", "eval/head_on/seed5/c2"))]
    estimate.print_plan_cost("screen of head_off against head_on", plan, "cpu", 2, "head_on")
    line = capsys.readouterr().err.strip()
    assert line.startswith("screen of head_off against head_on: 6 jobs to run (3 evaluate, 1 screen, 2 train), "
                           "2 training(s) (1 of them head_on's, the reference's) of 200000 env steps, about 0.7 h each "
                           "on this machine (its last calibration), of which about 0.1 h the teacher's 1500 episodes "
                           "and the cloning, 3 evaluations (2 of them head_on's) of about 50 s: about "), line
    # the two trainings side by side on 2 cores, then head_on's two evaluations one after the other
    hours = float(line.rsplit("about ", 1)[1].split(" h")[0])
    assert hours == round((200_000 / 100.0 + 360.0 + 2 * 50.0) / 3600, 1)
    assert estimate.plan_counts(plan) == {"evaluate": 3, "screen": 1, "train": 2, "total": 6}


def test_a_cost_line_that_reuses_a_busy_calibration_says_so(tmp_path, monkeypatch, capsys):
    """Issue 57: the cached calibration is shared by every checkout on the machine; one made while other
    processes kept cores busy is said wherever it is reused (a training's start, a comparison's cost line,
    `snakemake all`'s estimate), not only by the `estimate all` that made it."""
    import egosearch.cost.estimate as estimate
    from egosearch.cost import calibration

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(calibration, "CALIBRATION_CACHE", tmp_path / "rate.json")
    here = estimate.machine_key(calibration.this_machine())
    busy = ("this machine's last calibration was made while it was busy: other processes used 1.3 cores meanwhile, "
            "so its rate may be low and the estimate long (`egosearch estimate all` calibrates again: run it when "
            "the machine is idle)")
    results = tmp_path / "results" / "cpu"
    (results / "bench").mkdir(parents=True)
    (results / "provenance.json").write_text(json.dumps({"preset": "cpu", "jobs": [
        {"rule": "eval", "job": "x/seed0/kitchen_living/everywhere/h1.05", "wall_s": 40.0}]}))
    for other, said in ((1.3, True), (0.1, False), (None, False)):
        (tmp_path / "rate.json").write_text(json.dumps({"machine": here, "rate": 100.0, "steps": "body steps",
                                                        "other_load_cores": other}))
        assert (calibration.cached_busy_line() == busy) is said
        line = estimate.training_time_line(180_000, "cpu")
        assert line.startswith("estimate: about 0.5 h of CPU time") and line.endswith(f"; {busy}") is said
        estimate.print_plan_cost("screen of head_off against head_on", [training_job("head_off")], "cpu", 1,
                                 "head_on")
        err = capsys.readouterr().err
        assert "this machine (its last calibration)" in err and (f"  {busy}\n" in err) is said, err


def test_a_smoke_cost_line_prices_the_capped_config_in_minutes(tmp_path, monkeypatch, capsys):
    """Issue 73 item 3: head_on_25px pins 300,000 env steps, and a smoke dry run planned them (41 min); at smoke it
    trains the capped config's steps, and the line prices that config, from the cpu preset's stored run (smoke
    stores none), in minutes: the training at its env steps plus a job's start, an evaluation at the recorded time
    scaled to smoke's scenarios a cell."""
    import egosearch.cost.estimate as estimate
    from egosearch.variants import resolve_variant

    config = resolve_variant("head_on_25px", "smoke").config
    assert config.total_env_steps == 300 and not config.demo_episodes
    _calibrated_at_100_steps_a_second(tmp_path, monkeypatch)
    results = tmp_path / "results" / "cpu"
    (results / "bench").mkdir(parents=True)
    (results / "provenance.json").write_text(json.dumps({"preset": "cpu", "jobs": [
        {"rule": "eval", "job": "x/seed0/kitchen_living/everywhere/h1.05", "wall_s": 53.0}]}))
    plan = [training_job("head_on_25px"), evaluation_job("head_on_25px", 0, "c1", 1)]
    estimate.print_plan_cost("screen of head_on_25px against head_on", plan, "smoke", 1, "head_on",
                             scenarios_per_cell={"smoke": 4, "cpu": 200})
    line = capsys.readouterr().err.strip()
    training_s = config.total_env_steps / 100.0 + estimate.JOB_START_S
    evaluation_s = estimate.JOB_START_S + (53.0 - estimate.JOB_START_S) * 4 / 200
    assert (f"1 training(s) of {config.total_env_steps} env steps, about {training_s / 60:.1f} min each on this "
            "machine (its last calibration), 1 evaluations of about 4 s: "
            f"about {(training_s + evaluation_s) / 60:.1f} min on 1 core(s) (the smoke preset stores no run: priced "
            "from the cpu preset's") in line, line
    # without the cpu preset's run either, no estimate, as before
    (results / "provenance.json").unlink()
    estimate.print_plan_cost("screen of head_on_25px against head_on", plan, "smoke", 1, "head_on")
    assert "no estimate of the run's time: the smoke preset has no stored run" in capsys.readouterr().err
