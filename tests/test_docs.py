"""The docs pages: generated blocks wherever they live, the stored speed records, and a strict mkdocs build."""

import importlib.util
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from egosearch.cli import main
from egosearch.report.readme import BLOCK, BLOCKS, page_root, pages, update_pages

REPO = Path(__file__).resolve().parent.parent
needs_mkdocs = pytest.mark.skipif(importlib.util.find_spec("mkdocs") is None,
                                  reason="mkdocs is not installed (pip install -e '.[dev]')")


def _project(root: Path) -> None:
    """A project whose README and one docs page each hold a block read from the root's paper_figs/."""
    (root / "paper_figs" / "p").mkdir(parents=True)
    (root / "paper_figs" / "p" / "table1.md").write_text("| a |\n|---|\n| 0.42 |\n")
    block = "<!-- egosearch:begin table1 -->\nstale\n<!-- egosearch:end table1 -->\n"
    (root / "README.md").write_text("# r\n" + block)
    (root / "docs" / "deep").mkdir(parents=True)
    (root / "docs" / "deep" / "page.md").write_text("# d\ntext kept\n" + block)
    # the page's own folder holds stored files too: they must not be taken for the root's
    (root / "docs" / "deep" / "paper_figs" / "p").mkdir(parents=True)
    (root / "docs" / "deep" / "paper_figs" / "p" / "table1.md").write_text("| wrong |\n")


def test_blocks_in_docs_pages_read_the_project_root(tmp_path, monkeypatch, capsys):
    _project(tmp_path)
    page = tmp_path / "docs" / "deep" / "page.md"
    assert pages(tmp_path)[0] == tmp_path / "README.md" and page in pages(tmp_path)
    assert page_root(page) == tmp_path.resolve() and page_root(tmp_path / "README.md") == tmp_path.resolve()
    assert update_pages(tmp_path, "p", check=True) == [tmp_path / "README.md", page]
    assert "stale" in page.read_text()                      # check mode writes nothing
    monkeypatch.chdir(tmp_path)
    assert main(["report", "readme", "--preset", "p", "--check"]) == 2
    assert "README.md, docs/deep/page.md out of date" in capsys.readouterr().err
    assert main(["report", "readme", "--preset", "p"]) == 0
    for path in (tmp_path / "README.md", page):
        assert "| 0.42 |" in path.read_text() and "stale" not in path.read_text() and "wrong" not in path.read_text()
    assert "text kept" in page.read_text()
    assert main(["report", "readme", "--preset", "p", "--check"]) == 0
    # one page alone, as before the docs existed
    assert main(["report", "readme", "--preset", "p", "--check", "--readme", str(page)]) == 0


def test_every_block_lives_in_some_page():
    """Moving prose between the README and the docs must never drop a generated block."""
    names = {m["name"] for page in pages(REPO) for m in BLOCK.finditer(page.read_text(encoding="utf-8"))}
    assert set(BLOCKS) - names == set()


def test_every_stored_comparison_sits_on_its_familys_ablations_page():
    """A lever's stored comparisons follow its lines to ``docs/ablations/<family>.md``: none waits on the index."""
    from egosearch.report.readme import ABLATION_FAMILIES, block_compare

    assert block_compare(REPO, "cpu", unfiled=True).startswith("*None:")
    for family in ABLATION_FAMILIES:
        page = (REPO / "docs" / "ablations" / f"{family}.md").read_text(encoding="utf-8")
        assert f"<!-- egosearch:begin compare_{family} -->" in page, family


def test_the_departures_are_one_link_from_the_readme():
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    assert "docs/learner.md#departures-from-the-paper" in readme
    learner = (REPO / "docs" / "learner.md").read_text(encoding="utf-8")
    assert "## Departures from the paper\n" in learner and "<!-- egosearch:begin departures -->" in learner


def test_the_readme_keeps_the_commands_ci_runs():
    """.ci/run runs the README's test command first, then the slow tests it leaves out but for the
    exhaustive ones: the first must stay in the README as a command block, the second be named there."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    ci = [line for line in (REPO / ".ci" / "run").read_text().splitlines() if "-m pytest" in line]
    assert len(ci) == 2 and all(line.startswith("python3 -m pytest") for line in ci), ci
    assert "```bash\npython " + ci[0].removeprefix("python3 ") + "\n```" in readme
    assert ci[0].endswith('-m "not slow"') and ci[1].endswith('-m "slow and not exhaustive"')
    assert "`python " + ci[1].removeprefix("python3 ") + "`" in readme
    assert "```bash\nsnakemake --cores 2 all\n```" in readme


def test_no_exhaustive_test_is_left_in_this_run_unless_slow_ones_are(request):
    """An exhaustive test is marked slow too, so the README's ``-m "not slow"`` never selects it."""
    for item in request.session.items:
        if item.get_closest_marker("exhaustive"):
            assert item.get_closest_marker("slow"), f"{item.nodeid} is marked exhaustive but not slow"


def test_the_readme_is_a_two_minute_read_and_the_test_time_lives_there_only():
    """The README stays short (details in docs/), and the default test command's time is given in one place:
    the README's Run and test; a docs page naming the command points there instead of repeating a figure."""
    import re

    readme = (REPO / "README.md").read_text(encoding="utf-8")
    # 250: Table 1's three generated tables carry the tuned teacher's two bound rows per height
    assert len(readme.splitlines()) <= 250
    command = 'python -m pytest -q -n auto -m "not slow"'
    timed = re.compile(r"\d+ min \d+ s")
    after = readme.split(f"```bash\n{command}\n```", 1)[1]
    assert timed.search(after.split("\n\n", 2)[1]), "the README's test time follows its test command"
    for page in sorted((REPO / "docs").glob("*.md")):
        for line in page.read_text(encoding="utf-8").splitlines():
            if command in line:
                assert not timed.search(line) and "README" in line, f"{page.name}: {line}"


def test_the_readme_shows_making_the_env_in_one_line():
    import gymnasium

    readme = (REPO / "README.md").read_text(encoding="utf-8")
    block = readme.split("```python\n", 1)[1].split("\n```", 1)[0]
    # gymnasium imports the package named before the colon, which registers the ids: no other import
    # (tests/test_env_ids.py runs it in a fresh interpreter, where nothing was imported before)
    assert "\n" not in block and 'gymnasium.make("egosearch:EgoSearch-v0")' in block and "import egosearch" not in block
    import egosearch.envs  # noqa: F401  (this process imported egosearch before gymnasium: the ids come from here)

    scope: dict = {}
    exec(block, scope)  # the line as a reader pastes it
    try:
        assert set(scope["obs"]) == {"depth", "mask", "proprio"} and isinstance(scope["env"].unwrapped,
                                                                                  gymnasium.Env)
    finally:
        scope["env"].close()


def _record(result: dict, command: str, other: float = 0.02) -> dict:
    return {"command": command, "date_utc": "2026-01-02T03:04:05+00:00", "commit": "0123456789abcdef",
            "commit_dirty": False, "machine": {"cpu": "X CPU", "cores": 2}, "load_average_before": [0.1, 0.2, 0.3],
            "load_average_after": [0.9, 0.4, 0.3], "other_load_cores": other, "wall_s": 40.0, "result": result}


def test_speed_block_comes_from_the_stored_records(tmp_path):
    from egosearch.report.speed import block_speed

    text = block_speed(tmp_path, "p")
    assert "`results/p/bench/env.json` is missing" in text and "egosearch bench learner --json --out " \
        "results/p/bench/learner.json" in text                  # never invented when the file is absent
    bench = tmp_path / "results" / "p" / "bench"
    bench.mkdir(parents=True)
    (bench / "env.json").write_text(json.dumps(_record(
        {"layout": "kitchen_living", "triangles": 4604, "sensor_frames_per_s": 1234.5, "sensor_ms_per_frame": 0.81,
         "env_steps_per_s": 650.0, "env_ms_per_step": 1.538, "env_resets_included": 7}, "egosearch bench env")))
    (bench / "learner.json").write_text(json.dumps(_record(
        {"updates_per_s_naive": 3.1, "updates_per_s_naive_best": 3.3, "updates_per_s_table2": 4.2,
         "updates_per_s_table2_best": 4.4, "updates_per_s_cpu_profile": 60.5, "updates_per_s_cpu_profile_best": 62.0,
         "env_steps_per_core_s_cpu_profile": 151.2, "cpu_profile_run": {"env_steps": 4000, "core_s": 26.5},
         "updates_per_s_cpu_profile_avx2": 58.0, "env_steps_per_core_s_cpu_profile_avx2": 171.0,
         "replay_gb_100k": 1.156}, "egosearch bench learner", other=1.5)))
    train = tmp_path / "results" / "p" / "train" / "head_on" / "seed0"
    train.mkdir(parents=True)
    (train / "curve.csv").write_text("env_steps,success_rate,wall_s\n0,0.0,1.0\n300000,0.5,2000.0\n")
    # seed 1 shared its core: 3000 s of wall time, 1500 s of CPU time; seed 2 resumed (its job ran 500 s of 2000)
    benchmarks = tmp_path / "results" / "p" / "benchmarks" / "train" / "head_on"
    benchmarks.mkdir(parents=True)
    for seed, wall, job_wall, job_cpu in ((1, 3000.0, 3001.0, 1500.0), (2, 2000.0, 500.0, 480.0)):
        (train.parent / f"seed{seed}").mkdir()
        (train.parent / f"seed{seed}" / "curve.csv").write_text(f"env_steps,success_rate,wall_s\n300000,0.5,{wall}\n")
        (benchmarks / f"seed{seed}.tsv").write_text(f"s\th:m:s\tcpu_time\n{job_wall}\t0:50:00\t{job_cpu}\n")
    text = block_speed(tmp_path, "p")
    assert "**1,234 sensor frames/s** (0.81 ms a frame; target 1,000: met)" in text
    assert "**650 env steps/s** (1.538 ms a step, 7 resets included; target 700: not met)" in text
    assert "| `updates_per_s_table2` (" in text and "| 4.2 (4.4) |" in text and "| 60.5 (62.0) |" in text
    assert "target of 12: not met" in text and "**`env_steps_per_core_s_cpu_profile` 151.2**" in text
    assert "4,000-step" in text and "of 200: not met" in text
    assert "| `updates_per_s_cpu_profile_avx2` (" in text and "| 58.0 (–) |" in text
    assert "`ONEDNN_MAX_CPU_ISA=AVX2`, its own process): **171.0** env steps per core-second; the issue's target " \
        "of 170: met" in text
    # how busy the machine was is part of every figure
    assert "other processes used 1.50 cores meanwhile, load average 0.10 before" in text
    assert "X CPU with 2 cores" in text and "commit `0123456`" in text
    assert "| `head_on` | 0 | 300,000 | 2,000 | 1 | 150 | – | – |" in text       # no benchmark
    assert "| `head_on` | 1 | 300,000 | 3,000 | 1 | 100 | 1,500 | 200 |" in text
    assert "| `head_on` | 2 | 300,000 | 2,000 | 1 | 150 | – | – |" in text       # resumed: its job saw a quarter
    # a modular searcher's env step is a decision: its rates say so, and the body-step targets are not read on it
    record = json.loads((bench / "learner.json").read_text())
    record["result"]["cpu_profile_steps"] = "decisions"
    (bench / "learner.json").write_text(json.dumps(record))
    (train / "config.json").write_text(json.dumps({"env_id": "EgoSearchModular-v0", "config": {}}))
    text = block_speed(tmp_path, "p")
    assert "**`env_steps_per_core_s_cpu_profile` 151.2**: decisions per core-second of a 4,000-decision" in text
    assert "of 200: not met" not in text and "not comparable" in text and "of 170" not in text
    assert "| `head_on` | 0 | 300,000 decisions | 2,000 |" in text and "| `head_on` | 1 | 300,000 | 3,000 |" in text


def test_speed_block_gives_the_memory_levers_costs_from_their_records(tmp_path):
    from egosearch.report.speed import block_speed

    assert "memory levers" not in block_speed(tmp_path, "p")              # neither record: no section
    bench = tmp_path / "results" / "p" / "bench"
    bench.mkdir(parents=True)
    (bench / "env_memory_levers.json").write_text(json.dumps(_record(
        {"env_ms_per_step_by_option": {"none": 1.0, "map_image": 3.1, "strided_history": 1.2},
         "option_over_none": {"map_image": 3.1, "strided_history": 1.2}}, "egosearch bench env")))
    text = block_speed(tmp_path, "p")
    assert "| `map_image` | **3.10x** (3.1 against 1.0 ms) | – |" in text   # the learner's record is not stored
    (bench / "learner_memory_levers.json").write_text(json.dumps(_record(
        {"memory_levers": {"env_steps_per_core_s_plain": 90.0, "env_steps_per_core_s_map_image": 60.0,
                           "map_image_cost_ratio": 1.5}}, "egosearch bench learner --memory-levers", other=1.2)))
    text = block_speed(tmp_path, "p")
    assert ("| `map_image` | **3.10x** (3.1 against 1.0 ms) | **1.50x** (60.0 against 90.0 env steps per "
            "core-second) |") in text
    assert "| `strided_history` | **1.20x** (1.0" not in text and "| `strided_history` | **1.20x** (1.2 against" in text
    assert "`egosearch bench learner --memory-levers` on" in text and "other processes used 1.20 cores" in text


def test_every_machine_measured_is_a_row_of_the_speed_block_and_a_line_of_provenance(tmp_path):
    """A machine's own benchmark and estimate (``bench/hosts/<machine>/``) beside the benchmark machine's."""
    from egosearch.report.readme import block_provenance
    from egosearch.report.speed import block_speed

    bench = tmp_path / "results" / "p" / "bench"
    host = bench / "hosts" / "y-cpu-avx2-4-cores"
    host.mkdir(parents=True)
    result = {"updates_per_s_table2": 4.2, "updates_per_s_cpu_profile": 26.7, "cpu_profile_steps": "decisions",
              "env_steps_per_core_s_cpu_profile": 14.6, "env_steps_per_core_s_cpu_profile_avx2": 13.5}
    (bench / "learner.json").write_text(json.dumps(_record(result, "egosearch bench learner")))
    assert "every machine measured" not in block_speed(tmp_path, "p")        # one machine: no table of one row
    other = _record({**result, "env_steps_per_core_s_cpu_profile": 9.1, "updates_per_s_cpu_profile": 17.0},
                    "egosearch bench learner", other=0.0)
    other["machine"] = {"cpu": "Y CPU", "vector_unit": "AVX2", "cores": 4}
    (host / "learner.json").write_text(json.dumps(other))
    text = block_speed(tmp_path, "p")
    assert "| X CPU, 2 cores | the stored run's benchmark machine | 2026-01-02 (0.02) | 14.6 decisions (13.5) | " \
           "26.7 | 4.2 | – |" in text
    assert "| Y CPU (AVX2), 4 cores | `results/p/bench/hosts/y-cpu-avx2-4-cores/` | 2026-01-02 (0.00) | 9.1 " \
           "decisions (13.5) | 17.0 | 4.2 | – |" in text
    (host / "estimate_all.json").write_text(json.dumps({
        "date_utc": "2026-01-03T00:00:00+00:00", "machine": other["machine"], "cores": 2, "steps": "decisions",
        "hours_here": 4.25, "bench_rate": 9.0, "rate_source": "measured now"}))
    assert "| 17.0 | 4.2 | 4.2 h on 2 cores (calibrated at 9.0 decisions per CPU-second, measured now) |" in \
        block_speed(tmp_path, "p")
    # a finished run set beside the simulation of its own jobs
    (bench / "schedule_check.json").write_text(json.dumps({
        "command": "egosearch estimate check --log r.log", "date_utc": "2026-01-04T00:00:00",
        "machine": other["machine"],
        "target": "all", "cores": 2, "jobs": 139, "elapsed_s": 3000.0, "predicted_s": 2700.0,
        "own_times_simulated_s": 3060.0, "own_times_over_cores_s": 2950.0, "record_note": "139 of 139 jobs timed"}))
    assert ("139 jobs of `all` on 2 cores took **50.0 min**; predicted from the record before the run **45.0 min** "
            "(0.90 x; 139 of 139 jobs timed); its own job times laid out by the simulation 51.0 min (1.02 x); their "
            "sum / 2, the old lower bound, 49.2 min (`results/p/bench/schedule_check.json`).") in \
        block_speed(tmp_path, "p")
    # the provenance block names it beside the stored run's own estimate
    (tmp_path / "results" / "p" / "provenance.json").write_text(json.dumps({
        "preset": "p", "commit": "0123456789", "date_utc": "2026-01-02T03:04:05", "machine": {"cpu": "X CPU"},
        "jobs": [], "wall_s_all_jobs_summed": 0.0}))
    (bench / "estimate_all.json").write_text(json.dumps({
        "cores": 2, "steps": "decisions", "hours_as_recorded": 3.6, "hours_cpu_over_cores": 2.7}))
    assert ("The same DAG calibrated on the other machines measured (docs/speed.md): Y CPU (AVX2), 4 cores: 4.2 h on "
            "2 cores (calibrated at 9.0 decisions per CPU-second on 2026-01-03; "
            "`results/p/bench/hosts/y-cpu-avx2-4-cores/estimate_all.json`).") in block_provenance(tmp_path, "p")


def test_a_records_machine_placeholder_is_this_machines_folder(tmp_path, monkeypatch):
    from egosearch.core import machine

    assert machine.machine_folder_name({"cpu": "Intel(R) Xeon(R) Processor", "vector_unit": "AVX-512",
                                        "cores": 2}) == "intel-xeon-processor-avx-512-2-cores"
    assert machine.machine_folder_name({}) == "unknown-cores"
    assert machine.machine_folder_name({"cpu": "Intel(R) Xeon(R) Processor", "vector_unit": "AVX-512", "cores": 16,
                                        "gpu": "NVIDIA H100 80GB HBM3"}) == \
        "intel-xeon-processor-avx-512-16-cores-nvidia-h100-80gb-hbm3"
    monkeypatch.setattr(machine, "cpu_model", lambda: "AMD EPYC")
    monkeypatch.setattr(machine, "cpu_vector_unit", lambda: None)
    monkeypatch.setattr(machine.os, "cpu_count", lambda: 16)
    assert machine.with_machine("r/hosts/{machine}/learner.json") == "r/hosts/amd-epyc-16-cores/learner.json"
    assert machine.with_machine("r/learner.json") == "r/learner.json" and machine.with_machine(None) is None
    # the estimate's record says when, at which commit and where it was calibrated
    monkeypatch.chdir(REPO)
    out = tmp_path / "{machine}" / "estimate_all.json"
    assert main(["estimate", "all", "--rate", "10", "--out", str(out)]) == 0
    record = json.loads((tmp_path / "amd-epyc-16-cores" / "estimate_all.json").read_text())
    assert record["command"] == f"egosearch estimate all --cores 2 --preset cpu --rate 10 --out " \
        f"{tmp_path / 'amd-epyc-16-cores' / 'estimate_all.json'}" and record["machine"]["cores"] == 16
    assert record["date_utc"] and record["commit"] and record["bench_rate"] == 10


def test_bench_out_stores_the_result_with_its_machine_and_load(tmp_path, capsys):
    out = tmp_path / "bench" / "env.json"
    assert main(["bench", "env", "--frames", "20", "--steps", "20", "--out", str(out)]) == 0
    record = json.loads(out.read_text())
    assert record["command"] == "egosearch bench env --layout kitchen_living --frames 20 --steps 20"
    assert set(record) >= {"date_utc", "commit", "commit_dirty", "machine", "load_average_before", "other_load_cores"}
    assert record["machine"]["cores"] >= 1 and len(record["load_average_before"]) == 3
    assert record["result"]["layout"] == "kitchen_living" and record["result"]["env_steps_per_s"] > 0
    assert "other processes used" in capsys.readouterr().err


def _build(config: Path, site: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config), "-d", str(site)],
                          capture_output=True, text=True, timeout=300)


@needs_mkdocs
def test_mkdocs_builds_the_docs_strictly_with_the_stored_figures(tmp_path):
    run = _build(REPO / "mkdocs.yml", tmp_path / "site")
    assert run.returncode == 0, run.stderr
    nav_pages = {p.relative_to(REPO / "docs").with_suffix("").as_posix() for p in (REPO / "docs").rglob("*.md")}
    for stem in nav_pages - {"index"}:
        assert (tmp_path / "site" / stem / "index.html").is_file(), stem
    # the figures the pages show from paper_figs/ are in the site, and the pages point at them
    results = (tmp_path / "site" / "results" / "index.html").read_text()
    assert 'src="../paper_figs/cpu/fig6.png"' in results
    assert (tmp_path / "site" / "paper_figs" / "cpu" / "fig6.png").read_bytes() == \
        (REPO / "paper_figs" / "cpu" / "fig6.png").read_bytes()
    assert not (tmp_path / "site" / "hooks.py").exists()
    # the one generated page: every learner's config, made by the hook at each build, never kept in git
    config = (tmp_path / "site" / "config" / "index.html").read_text()
    assert "Shared by every learner" in config and "critic_privileged_state" in config


@needs_mkdocs
def test_strict_build_still_fails_on_a_broken_link_or_anchor(tmp_path):
    """The hook publishes linked repository files; it must not hide a link to nothing."""
    shutil.copy(REPO / "mkdocs.yml", tmp_path / "mkdocs.yml")
    text = (tmp_path / "mkdocs.yml").read_text()
    nav = text[text.index("nav:"):text.index("# The pages show")]
    (tmp_path / "mkdocs.yml").write_text(text.replace(nav, "nav:\n  - Home: index.md\n  - Other: other.md\n"))
    (tmp_path / "docs").mkdir()
    shutil.copy(REPO / "docs" / "hooks.py", tmp_path / "docs" / "hooks.py")
    (tmp_path / "figs").mkdir()
    (tmp_path / "figs" / "a.png").write_bytes(b"png")
    (tmp_path / "docs" / "other.md").write_text("# Other\n\n## A part\n")
    index = tmp_path / "docs" / "index.md"
    index.write_text("# Home\n\n![a](../figs/a.png) and [a part](other.md#a-part)\n")
    run = _build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "site" / "figs" / "a.png").read_bytes() == b"png"
    for broken, named in (("![b](../figs/missing.png)", "missing.png"), ("[c](other.md#no-such-part)", "no-such-part")):
        index.write_text(f"# Home\n\n{broken}\n")
        run = _build(tmp_path / "mkdocs.yml", tmp_path / "site")
        assert run.returncode != 0 and named in run.stderr + run.stdout
