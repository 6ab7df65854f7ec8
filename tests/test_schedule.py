"""The simulated schedule of `snakemake --cores N`: hand-worked cases, the durations a provenance
record gives, the scaling of trainings to another machine, and the real DAG at the smoke preset."""

import pytest

from egosearch.cost.schedule import (
    durations_from_provenance,
    machine_key,
    machine_rates,
    scale_to_rate,
    scale_trainings,
    simulate,
    spread,
    training_rates,
)

H = 3600.0


def job(ident, threads=1, deps=(), order=0, **extra):
    rule = ident.split("/")[0]
    return {"id": ident, "rule": rule, "threads": threads, "deps": list(deps), "order": order,
            "record_rule": rule, "job": ident.partition("/")[2] or None, **extra}


def trainings(n, threads=1):
    return [job(f"train/v/seed{i}", threads=threads, order=i) for i in range(n)]


def test_six_one_thread_trainings_on_two_cores_run_in_three_waves():
    jobs = trainings(6)
    s = simulate(jobs, 2, {j["id"]: H for j in jobs})
    assert s.makespan == 3 * H
    # the waves: two at 0 h, two at 1 h, two at 2 h
    assert sorted(s.start.values()) == [0, 0, H, H, 2 * H, 2 * H]


def test_six_two_thread_trainings_on_two_cores_run_one_at_a_time():
    jobs = trainings(6, threads=2)
    s = simulate(jobs, 2, {j["id"]: H for j in jobs})
    assert s.makespan == 6 * H
    assert sorted(s.start.values()) == [i * H for i in range(6)]


def test_two_one_thread_jobs_on_two_cores_run_side_by_side():
    jobs = [job("eval/a", order=0), job("eval/b", order=1)]
    s = simulate(jobs, 2, {"eval/a": 100.0, "eval/b": 60.0})
    assert s.start == {"eval/a": 0.0, "eval/b": 0.0}
    assert s.makespan == 100.0


def test_a_job_waits_for_its_dependency_even_with_a_core_free():
    jobs = [job("train/v/seed0", order=0), job("eval/v/seed0/x", deps=["train/v/seed0"], order=1)]
    s = simulate(jobs, 2, {"train/v/seed0": 500.0, "eval/v/seed0/x": 40.0})
    assert s.start["eval/v/seed0/x"] == 500.0
    assert s.makespan == 540.0
    assert s.critical_path == ["train/v/seed0", "eval/v/seed0/x"]


def test_a_job_asking_more_threads_than_cores_gets_them_all_and_runs_alone():
    jobs = [job("train/big", threads=8, order=0), job("eval/small", order=1)]
    s = simulate(jobs, 2, {"train/big": 10.0, "eval/small": 3.0})
    assert s.threads["train/big"] == 2
    # the big job first (job order), alone; the small one after it
    assert s.start == {"train/big": 0.0, "eval/small": 10.0}
    assert s.makespan == 13.0


def test_imperfect_packing_is_longer_than_cpu_time_over_cores():
    # three one-hour jobs on two cores: the third runs alone in the second hour
    jobs = trainings(3)
    s = simulate(jobs, 2, {j["id"]: H for j in jobs})
    assert s.makespan == 2 * H
    assert s.packing_bound == 1.5 * H
    assert s.utilisation == 0.75


def test_a_dependency_chain_is_longer_than_cpu_time_over_cores():
    # a 1 h training then a 1 h evaluation, beside a 0.5 h job: 2 h, not (1 + 1 + 0.5) / 2 = 1.25 h
    jobs = [job("train/v/seed0", order=0), job("eval/v/seed0/x", deps=["train/v/seed0"], order=1),
            job("bound/r", order=2)]
    s = simulate(jobs, 2, {"train/v/seed0": H, "eval/v/seed0/x": H, "bound/r": 0.5 * H})
    assert s.makespan == 2 * H
    assert s.packing_bound == 1.25 * H
    assert s.longest_chain == ["train/v/seed0", "eval/v/seed0/x"]
    assert s.longest_chain_s == 2 * H
    assert s.lower_bound == 2 * H


def test_the_order_of_starting_changes_the_makespan_and_priority_sets_it():
    # two cores, two 2 h trainings and four 1 h jobs. By job order the trainings go first (0-2 h),
    # then the short jobs two at a time (2-4 h): 4 h. With one training at a lower priority, the
    # other and the short jobs fill 0-3 h and it runs alone at the end: 3-5 h. Both trainings last:
    # the short jobs 0-2 h, the trainings 2-4 h: 4 h again.
    longs = [job("train/a", order=0), job("train/b", order=1)]
    shorts = [job(f"eval/{i}", order=2 + i) for i in range(4)]
    durations = {"train/a": 2 * H, "train/b": 2 * H} | {f"eval/{i}": H for i in range(4)}
    assert simulate(longs + shorts, 2, durations).makespan == 4 * H
    s = simulate([longs[0], dict(longs[1], priority=-1)] + shorts, 2, durations)
    assert s.start["train/b"] == 3 * H
    assert s.makespan == 5 * H
    assert s.slowest(2) == [("train/a", 2 * H), ("train/b", 2 * H)]
    s = simulate([dict(j, priority=-1) for j in longs] + shorts, 2, durations)
    assert s.start == {"train/a": 2 * H, "train/b": 2 * H, "eval/0": 0.0, "eval/1": 0.0, "eval/2": H, "eval/3": H}
    assert s.makespan == 4 * H


def test_larger_inputs_start_first_among_equal_priorities_as_greedy_does():
    jobs = [job("train/a", order=0), job("eval/small", order=1, input_bytes=10),
            job("eval/big", order=2, input_bytes=1000)]
    s = simulate(jobs, 1, {"train/a": 5.0, "eval/small": 1.0, "eval/big": 1.0})
    assert s.rows()[0]["id"] == "eval/big"
    assert [r["id"] for r in s.rows()] == ["eval/big", "eval/small", "train/a"]
    # without input sizes (the ILP's objective here): job order
    s = simulate(jobs, 1, {"train/a": 5.0, "eval/small": 1.0, "eval/big": 1.0}, input_sizes=False)
    assert [r["id"] for r in s.rows()] == ["train/a", "eval/small", "eval/big"]


def test_a_job_that_fits_starts_beside_one_waiting_for_more_cores():
    # three cores: a 2-thread job runs; a 2-thread job first in order does not fit on the one free
    # core, the 1-thread job behind it does
    jobs = [job("a", threads=2, order=0), job("b", threads=2, order=1), job("c", threads=1, order=2)]
    s = simulate(jobs, 3, {"a": 10.0, "b": 10.0, "c": 4.0})
    assert s.start == {"a": 0.0, "b": 10.0, "c": 0.0}
    assert s.makespan == 20.0


def test_critical_path_follows_a_wait_for_a_core():
    # one core: b waits for a's core, c for b's (no dependencies): all three are the path
    jobs = [job("a", order=0), job("b", order=1), job("c", order=2)]
    s = simulate(jobs, 1, {"a": 1.0, "b": 2.0, "c": 3.0})
    assert s.critical_path == ["a", "b", "c"]
    assert s.makespan == 6.0


def test_spread_is_reproducible_and_never_beats_the_lower_bound():
    jobs = trainings(3) + [job(f"eval/{i}", order=10 + i) for i in range(4)]
    durations = {j["id"]: (H if j["rule"] == "train" else 0.25 * H) for j in jobs}
    makespans = spread(jobs, 2, durations, runs=30, seed=1)
    assert makespans == spread(jobs, 2, durations, runs=30, seed=1)
    assert makespans == sorted(makespans)
    bound = simulate(jobs, 2, durations).lower_bound
    assert all(m >= bound for m in makespans)


def test_cycles_and_unknown_dependencies_are_refused():
    with pytest.raises(ValueError, match="not a job"):
        simulate([job("a", deps=["nope"])], 1, {"a": 1.0})
    with pytest.raises(ValueError, match="never became ready"):
        simulate([job("a", deps=["b"]), job("b", deps=["a"])], 1, {"a": 1.0, "b": 1.0})
    with pytest.raises(ValueError, match="duration"):
        simulate([job("a")], 1, {})


RECORD = {"jobs": [
    {"rule": "train", "job": "v/seed0", "wall_s": 1000.0, "cpu_s": 900.0, "machine": {"cpu": "Slow", "cores": 2}},
    # resumed: the benchmark timed the last half; run_wall_s is the whole run
    {"rule": "train", "job": "v/seed1", "wall_s": 400.0, "cpu_s": 400.0, "run_wall_s": 800.0,
     "machine": {"cpu": "Fast", "cores": 2}},
    {"rule": "eval", "job": "v/seed0/x", "wall_s": 30.0},
    {"rule": "eval", "job": "v/seed1/x", "wall_s": 50.0},
    {"rule": "report", "job": "table1", "wall_s": 5.0},
]}
DAG = [job("train/v/seed0", order=0), job("train/v/seed1", order=1), job("train/v/seed2", order=2),
       job("eval/v/seed0/x", deps=["train/v/seed0"], order=3), job("eval/v/seed1/x", deps=["train/v/seed1"], order=4),
       job("eval/v/seed2/x", deps=["train/v/seed2"], order=5),
       job("report/fig6", deps=["eval/v/seed0/x"], order=6),
       {"id": "all", "rule": "all", "threads": 1, "deps": ["report/fig6"], "order": 7}]


def test_durations_come_from_the_record_with_whole_runs_medians_and_zeros():
    d = durations_from_provenance(RECORD, DAG)
    assert d["train/v/seed0"] == 1000.0
    assert d["train/v/seed1"] == 800.0  # run_wall_s, not the resumed part
    assert d["train/v/seed2"] == 900.0  # missing: the median of the DAG's trainings found, (1000 + 800) / 2
    assert d["eval/v/seed2/x"] == 40.0
    assert d["report/fig6"] == 0.0  # a report rule missing from the record
    assert d["all"] == 0.0
    assert d.missing == ["train/v/seed2", "eval/v/seed2/x", "report/fig6"]
    assert d.untimed == ["all"]
    assert "3 not in the record" in d.note() and "1 without a benchmark" in d.note()


def test_scale_multiplies_trainings_and_other_scale_the_rest():
    d = durations_from_provenance(RECORD, DAG, scale=2.0, other_scale=0.5)
    assert d["train/v/seed0"] == 2000.0
    assert d["eval/v/seed0/x"] == 15.0
    assert d["all"] == 0.0
    s = simulate(DAG, 2, d)
    # hand-worked: seed0 (2000 s) and seed1 (1600 s) start at 0; at 1600 s seed2 (the median 900 s
    # of the record's two, x2) comes before seed1's evaluation in job order and runs 1600-3400 s;
    # the other core takes the evaluations of seed0 (15 s) and seed1 (25 s) from 2000 s; seed2's
    # evaluation (the median 40 s, x0.5) ends the run at 3420 s
    assert s.start["train/v/seed2"] == 1600.0
    assert s.start["eval/v/seed1/x"] == 2015.0
    assert s.makespan == 3420.0


def test_trainings_scaled_to_the_slowest_machine():
    steps = {"v/seed0": 9000, "v/seed1": 16000}
    rates = training_rates(RECORD, steps)
    # steps per whole-run CPU second: 9000 / 900; 16000 / (400 * 800 / 400)
    assert rates == {"v/seed0": 10.0, "v/seed1": 20.0}
    by_machine = machine_rates(RECORD, rates)
    assert by_machine == {"Slow / ? / 2 cores": 10.0, "Fast / ? / 2 cores": 20.0}
    d = durations_from_provenance(RECORD, DAG)
    slow = scale_trainings(d, RECORD["jobs"], by_machine, min(by_machine.values()))
    assert slow["train/v/seed0"] == 1000.0  # already on the slow machine
    assert slow["train/v/seed1"] == 1600.0  # twice as slow there
    assert slow["train/v/seed2"] == d["train/v/seed2"]  # no record, no machine: left as it was
    assert slow.unscaled == ["train/v/seed2"]
    assert slow.scaled == {"train/v/seed1": 2.0}
    # a host whose rate is half the slow machine's: every placed training twice as long as there
    half = scale_to_rate(d, rates, 5.0)
    assert half["train/v/seed0"] == 2000.0 and half["train/v/seed1"] == 3200.0
    assert half["eval/v/seed0/x"] == d["eval/v/seed0/x"]


def test_on_cores_of_their_own_jobs_take_their_cpu_time_and_trainings_their_steps_at_a_rate():
    from egosearch.cost.schedule import trainings_at_rate

    own = durations_from_provenance(RECORD, DAG, own_cores=True)
    assert own["train/v/seed0"] == 900.0  # its CPU time, not its 1,000 s of wall time
    assert own["train/v/seed1"] == 800.0  # 400 CPU-s of a 400 s part, scaled to the 800 s run
    assert own["eval/v/seed0/x"] == 30.0  # no CPU time recorded: its wall time
    assert "CPU time" in own.note()
    # at 20 env steps per CPU-s: seed0's 9,000 steps take 450 s, plus its 100 s of imitation; seed1 has no
    # imitation recorded (it is left as it was, and said so); seed2 has no steps
    at = trainings_at_rate(own, {"v/seed0": 9000, "v/seed1": 16000}, {"v/seed0": 100.0}, 20.0)
    assert at["train/v/seed0"] == 550.0
    assert at["train/v/seed1"] == 800.0 and at["train/v/seed2"] == own["train/v/seed2"]
    assert at.at_rate == ["train/v/seed0"] and at.unscaled == ["train/v/seed1", "train/v/seed2"]
    assert "1 trainings at the rate" in at.note()
    with pytest.raises(ValueError, match="positive"):
        trainings_at_rate(own, {}, {}, 0.0)


def test_machine_key_names_what_was_not_recorded():
    assert machine_key(None) == "unknown"
    assert machine_key({"cpu": "AMD EPYC", "vector_unit": None, "cores": 2}) == "AMD EPYC / ? / 2 cores"


@pytest.mark.slow
def test_the_smoke_dag_trains_before_it_evaluates():
    from egosearch.workflow.dag import dag_jobs

    jobs = dag_jobs("all", cores=2, config={"preset": "smoke"})
    by_id = {j.id: j for j in jobs}
    trains = [j for j in jobs if j.rule == "train"]
    assert trains and all(j.record_rule == "train" for j in trains)
    for j in trains:
        variant, seed = j.job.split("/")
        assert seed.startswith("seed") and seed[len("seed"):].isdigit() and variant
        assert j.id == f"train/{j.job}" and j.deps == ()
    evals = [j for j in jobs if j.rule == "evaluate"]
    assert evals
    for j in evals:
        assert j.record_rule == "eval"
        variant, seed = j.job.split("/")[:2]
        assert f"train/{variant}/{seed}" in j.deps
        # each job's own wildcards (the schedule check matches a run's log against them)
        assert j.wildcards["variant"] == variant and f"seed{j.wildcards['seed']}" == seed
        assert j.job.endswith(f"/{j.wildcards['placement']}/h{j.wildcards['height']}")
    assert all(d in by_id for j in jobs for d in j.deps)
    assert all(1 <= j.threads <= 2 for j in jobs)
    assert {j.rule for j in jobs if j.job is None} >= {"all", "provenance"}
    s = simulate(jobs, 2, {j.id: 1.0 for j in jobs})
    for j in evals:
        variant, seed = j.job.split("/")[:2]
        assert s.start[j.id] >= s.end[f"train/{variant}/{seed}"]
