"""The README's results blocks are generated from the stored files, never typed."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pandas as pd
import pytest

from egosearch.cli import main
from egosearch.report.readme import render_readme, update_readme

REPO = Path(__file__).resolve().parent.parent
STORED_RUN = [REPO / "results" / "cpu" / "provenance.json", REPO / "results" / "cpu" / "eval" / "head_on"]
needs_stored_run = pytest.mark.skipif(
    not all(p.exists() for p in STORED_RUN),
    reason="the stored run of the current cpu preset is not committed yet (see the README's Results status)")


def copy_stored_cpu_results(dest: Path) -> None:
    """The committed files of results/cpu (git's list): a working copy also holds runs in progress,
    whose files the provenance does not list yet."""
    listed = subprocess.run(["git", "ls-files", "-z", "results/cpu"], cwd=REPO, capture_output=True, text=True)
    names = [n for n in listed.stdout.split("\0") if n] if listed.returncode == 0 else []
    if not names:   # not a git checkout: everything but what a running training keeps
        shutil.copytree(REPO / "results" / "cpu", dest, ignore=shutil.ignore_patterns("ckpt", "partial", "*.pt"))
        return
    for name in names:
        target = dest / Path(name).relative_to("results/cpu")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(REPO / name, target)


def _stored_results(root: Path) -> None:
    figs, results = root / "paper_figs" / "p", root / "results" / "p"
    figs.mkdir(parents=True)
    results.mkdir(parents=True)
    (figs / "table1.md").write_text("| a | b |\n|---|---|\n| 0.42 | 0.17 |\n\n")
    pd.DataFrame({"variant": ["v", "v", "w"], "label": ["v", "v", "w"], "env_steps": [0, 4000, 0],
                  "n_seeds": [3, 3, 1], "success_rate": [0.1, 0.3, 0.05], "low": [0.0, 0.2, float("nan")],
                  "high": [0.2, 0.4, float("nan")]}).to_csv(figs / "fig6.csv", index=False)
    (results / "provenance.json").write_text(json.dumps({
        "preset": "p", "commit": "0123456789abcdef", "date_utc": "2026-01-02T03:04:05+00:00",
        "machine": {"cpu": "X", "cores": 2, "torch": "2"}, "wall_s_per_rule_summed": {"train": 10800.0, "eval": 60.0},
        "wall_s_all_jobs_summed": 10860.0, "note": "resumed once",
        # head_on's training shared a core: it ran 3600 s of its 7200 (its CPU time)
        "jobs": [{"rule": "train", "job": "head_on/seed0", "wall_s": 7200.0, "cpu_s": 3600.0},
                 {"rule": "eval", "job": "head_off/seed0/kitchen_living/everywhere/h1.05", "wall_s": 60.0},
                 {"rule": "train", "job": "my_variant/seed0", "wall_s": 3600.0},
                 {"rule": "train", "job": "head_on_generated_homes/seed0", "wall_s": 1800.0},
                 {"rule": "eval", "job": "head_on/seed0/generated_heldout/everywhere/h1.05", "wall_s": 30.0},
                 {"rule": "bound", "job": "oracle/seed0/generated_train/everywhere/h1.05", "wall_s": 30.0},
                 {"rule": "report", "job": "generalise", "wall_s": 12.0},
                 {"rule": "report", "job": "table1", "wall_s": 12.0},
                 {"rule": "report", "job": "budget", "wall_s": 12.0},
                 {"rule": "traces", "job": "head_on/seed0/kitchen_living/everywhere/h1.05", "wall_s": 24.0}]}))


README = """# t
<!-- egosearch:begin table1 -->
stale
<!-- egosearch:end table1 -->
text kept
<!-- egosearch:begin fig6 -->
<!-- egosearch:end fig6 -->
<!-- egosearch:begin provenance -->
<!-- egosearch:end provenance -->
<!-- egosearch:begin fig7 -->
<!-- egosearch:end fig7 -->
"""


def test_blocks_are_filled_from_the_stored_files(tmp_path):
    _stored_results(tmp_path)
    out = render_readme(README, tmp_path, "p")
    assert "stale" not in out and "| 0.42 | 0.17 |" in out and "text kept" in out
    # fig6: first, last (with its seed CI) and best evaluation of each variant
    assert "| v | 3 | 0.10 | 0.30 [0.20, 0.40] at 4,000 | +0.20 | seeds | 0.30 at 4,000 |" in out
    assert "| w | 1 | 0.05 | 0.05 [–, –] at 0 | +0.00 | seeds | 0.05 at 0 |" in out
    assert "commit `0123456`" in out and "10 jobs, 3.02 h" in out and "eval 1.0 min, train 180.0 min" in out
    # `all` trains head_on and head_off only: my_variant's hour is a comparison, not part of it; the
    # generated-homes variant, the generated groups and the generalise report are `generalise`'s
    # ... each at its CPU time where recorded: head_on's training counts 3600 s, not its 7200 s of wall time
    # without a simulated estimate stored (results/p/bench/estimate_all.json), the lower bound, named so
    assert ("Lower bound of `snakemake --cores 2 all` from a fresh clone (its jobs' summed CPU time / 2, as if they "
            "packed perfectly): 0.51 h") in out
    assert "`snakemake --cores 2 generalise` 0.52 h of job CPU time" in out
    assert "comparisons and studies (compare, budget, fresh, the traces) 1.01 h" in out
    assert "resumed once" in out
    assert "*Not generated yet: `paper_figs/p/fig7.csv` is missing" in out     # never invented when the file is absent
    assert render_readme(out, tmp_path, "p") == out         # idempotent


def test_check_mode_reports_stale_blocks_without_writing(tmp_path):
    _stored_results(tmp_path)
    readme = tmp_path / "README.md"
    readme.write_text(README)
    assert update_readme(readme, "p", check=True) is False
    assert readme.read_text() == README
    assert update_readme(readme, "p") is False              # rewritten now
    assert update_readme(readme, "p", check=True) is True
    assert main(["report", "readme", "--readme", str(readme), "--preset", "p", "--check"]) == 0
    (tmp_path / "paper_figs" / "p" / "table1.md").write_text("| a |\n|---|\n| 0.43 |\n")
    assert main(["report", "readme", "--readme", str(readme), "--preset", "p", "--check"]) == 2


def test_compare_blocks_list_every_stored_comparison_on_its_familys_page(tmp_path):
    folder = tmp_path / "results" / "p" / "compare"
    folder.mkdir(parents=True)
    row = dict(height=1.05, placement="everywhere", metric="success", reference=0.01, candidate=0.1, difference=0.09,
               ci_low=0.05, ci_high=0.13, p_uncorrected=0.0001, p_holm=0.001, significant_holm=True, n_scenarios=100,
               n_seeds_ref=3, n_seeds_cand=3)
    pd.DataFrame([row, {**row, "metric": "spl", "p_uncorrected": 0.03, "p_holm": 0.06,
                        "significant_holm": False}]).to_csv(
        folder / "my_new_variant_vs_head_on.csv", index=False)
    unfiled = "<!-- egosearch:begin compare_unfiled -->\n<!-- egosearch:end compare_unfiled -->"
    memory = "<!-- egosearch:begin compare_memory -->\n<!-- egosearch:end compare_memory -->"
    assert "every stored comparison is on its family's page" in render_readme(unfiled, tmp_path, "p2")
    assert "No stored comparison of these levers yet" in render_readme(memory, tmp_path, "p")
    out = render_readme(unfiled, tmp_path, "p")                  # a lever no family names waits on the index
    assert "`my_new_variant` vs `head_on` (difference" in out     # no homes column: no homes named
    assert "| 1.05 | everywhere | success | 0.010 | 0.100 | +0.090 [+0.050, +0.130] | 0.0001 | 0.001 * |" in out
    assert "| 1.05 | everywhere | spl | 0.010 | 0.100 | +0.090 [+0.050, +0.130] | 0.03 | 0.06 |" in out
    pd.DataFrame([{**row, "homes": "bedroom_bath"}]).to_csv(folder / "my_new_variant_vs_head_on.csv", index=False)
    assert "`my_new_variant` vs `head_on` in bedroom_bath (difference" in render_readme(unfiled, tmp_path, "p")
    # a screen of a family's lever, whatever its seeds, sits on that family's page and nowhere else
    pd.DataFrame([row]).to_csv(folder / "screen_head_on_map_image_seeds0-2_vs_head_on.csv", index=False)
    assert "`screen_head_on_map_image_seeds0-2` vs `head_on`" in render_readme(memory, tmp_path, "p")
    assert "head_on_map_image" not in render_readme(unfiled, tmp_path, "p")
    assert "my_new_variant" not in render_readme(memory, tmp_path, "p")


def test_comparison_family_reads_the_candidate_lever():
    from egosearch.report.readme import comparison_family

    assert comparison_family("screen_head_on_contact_signal_seeds0-1_vs_head_on_imitation_finetune") == "stuck"
    assert comparison_family("screen_head_on_imitation_seed0_vs_head_on_from_scratch_seed0") == "imitation"
    assert comparison_family("head_on_from_scratch_vs_head_on_25px") == "resolution"
    assert comparison_family("head_on_vs_frontier") == "references"
    assert comparison_family("head_on_vs_head_on_imitation_finetune") == "stuck"   # named on its own
    assert comparison_family("screen_head_on_paper_homes_seed0_vs_head_on_kitchen_living_seed0_in_bedroom_bath") == \
        "references"
    assert comparison_family("my_new_variant_vs_head_on") is None


def test_generalise_block_says_when_it_shows_the_one_seed_screen(tmp_path):
    text = "<!-- egosearch:begin generalise -->\n<!-- egosearch:end generalise -->"
    assert "`paper_figs/p/generalise.md` is missing (run `snakemake --cores 2 generalise`)" in render_readme(
        text, tmp_path, "p")
    figs = tmp_path / "paper_figs" / "p"
    figs.mkdir(parents=True)
    (figs / "generalise_seed0.md").write_text("| variant | x |\n|---|---|\n| head_on | 0.42 |\n")
    out = render_readme(text, tmp_path, "p")
    assert "One seed per policy (seed 0)" in out and "| head_on | 0.42 |" in out
    (figs / "generalise.md").write_text("| variant | x |\n|---|---|\n| head_on | 0.51 |\n")
    out = render_readme(text, tmp_path, "p")
    assert "One seed" not in out and "| head_on | 0.51 |" in out and "`paper_figs/p/generalise.png`" in out


def _write_reading_inputs(root: Path) -> None:
    figs = root / "paper_figs" / "cpu"
    figs.mkdir(parents=True)
    rows = []
    cells = [(0.45, "no_low_cabinets", 0.20, 0.15, 0.25), (1.05, "no_low_cabinets", 0.85, 0.80, 0.90),
             (0.45, "everywhere", 0.50, 0.45, 0.55), (1.05, "everywhere", 0.55, 0.50, 0.60)]
    for (h, pl, rate, lo, hi) in cells:
        rows.append({"home": "both", "height": h, "placement": pl, "success_rate": rate, "ci_low": lo, "ci_high": hi,
                     "random_success_rate": 0.0, "oracle_success_rate": 1.0})
        # a home's own row is not the one set beside the paper: the reading must skip it
        rows.append({"home": "kitchen_living", "height": h, "placement": pl, "success_rate": 0.99, "ci_low": 0.98,
                     "ci_high": 1.0, "random_success_rate": 0.0, "oracle_success_rate": 1.0})
    pd.DataFrame(rows).to_csv(figs / "table1.csv", index=False)
    pd.DataFrame([{"variant": v, "env_steps": s, "success_rate": r, "low": lo, "high": hi}
                  for v, s, r, lo, hi in [("head_on", 0, 0.0, 0.0, 0.0), ("head_on", 100, 0.6, 0.5, 0.7),
                                          ("head_off", 100, 0.3, 0.2, 0.4)]]).to_csv(figs / "fig6.csv", index=False)
    pd.DataFrame([{"method": m, "label": lab, "M": M, "spl": spl, "spl_low": lo, "spl_high": hi, "attempts": att}
                  for m, lab, M, spl, lo, hi, att in [("one_step_short", "1-step short", 5, 0.10, 0.05, 0.15, 9.0),
                                                      ("ours", "ours", 1, 0.50, 0.45, 0.55, 60.0),
                                                      ("ours", "ours", 20, 0.12, 0.08, 0.16, 3.0)]]
                 ).to_csv(figs / "fig7.csv", index=False)
    # head off against head on on every Table 1 scenario: lower by 0.30 at 0.45 m excl. (after Holm), by 0.02 at
    # 1.05 m everywhere (not after Holm)
    compare = root / "results" / "cpu" / "compare"
    compare.mkdir(parents=True)
    pd.DataFrame([{"height": h, "placement": pl, "metric": "success", "difference": d, "ci_low": lo, "ci_high": hi,
                   "significant_holm": sig}
                  for h, pl, d, lo, hi, sig in [(0.45, "no_low_cabinets", -0.30, -0.40, -0.20, True),
                                                (1.05, "everywhere", -0.02, -0.08, 0.04, False)]]
                 ).to_csv(compare / "head_off_vs_head_on.csv", index=False)


def test_reading_block_states_what_the_stored_numbers_show(tmp_path):
    """Hand-made numbers: which cells are within 0.10 of the paper (0.50, 0.92, 0.58, 0.75), which
    intervals are apart, and the direction of M."""
    from egosearch.report.readme import block_reading

    _write_reading_inputs(tmp_path)
    text = block_reading(tmp_path, "cpu")
    assert "within 0.10 of the paper's success rate in 2 of 4 cells" in text  # 1.05 excl and 0.45 everywhere
    assert "0.45 m no low cabinets 0.20 vs 0.50" in text and "1.05 m everywhere 0.55 vs 0.75" in text
    assert "every cell sits 0.20–0.85 of the way" in text
    # excluding cabinets: 0.85 - 0.20 = +0.65, paper 0.92 - 0.50 = +0.42; everywhere 0.55 - 0.50, paper 0.75 - 0.58
    assert "minus 0.45 m is +0.65 (paper: +0.42); 1.05 m minus 0.45 m +0.65: intervals apart" in text
    assert "minus 0.45 m is +0.05 (paper: +0.17); 1.05 m minus 0.45 m +0.05: intervals overlap" in text
    assert ("head-on minus head-off is 0.45 m excl. +0.300 [+0.200, +0.400]; 1.05 m everywhere +0.020 [-0.040, "
            "+0.080] (95% intervals); head-off is lower after Holm in 1 of 2 cells") in text
    assert "1-step short 0.10 (ours' interval above theirs at 1 of 2 M)" in text
    assert "SPL falls from 0.50 at M=1 to 0.12 at M=20 (intervals apart); attempts fall from 60.0 to 3.0" in text


def test_unknown_block_is_an_error(tmp_path):
    with pytest.raises(ValueError, match="'tabel1' is unknown"):
        render_readme("<!-- egosearch:begin tabel1 -->\n<!-- egosearch:end tabel1 -->", tmp_path, "p")


def test_the_repository_readme_and_docs_match_the_stored_cpu_results():
    from egosearch.report.readme import pages, update_pages

    assert REPO / "README.md" in pages(REPO) and REPO / "docs" / "results.md" in pages(REPO)
    stale = update_pages(REPO, "cpu", check=True)
    assert stale == [], (f"generated blocks of {', '.join(str(p.relative_to(REPO)) for p in stale)} differ from "
                         "results/cpu + paper_figs/cpu: run `egosearch report readme --preset cpu`")


def test_the_readings_contrasts_read_the_presets_seeds_only(tmp_path):
    """head_on also stores the reference's spread seeds beyond the preset's (`snakemake seed_spread`): the
    reading's height and cabinet contrasts are Table 1's, read on the preset's seeds alone."""
    import yaml

    from egosearch.report.readme import table1_contrast

    config = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())
    seeds, spread = config["presets"]["cpu"]["seeds"], config["presets"]["cpu"]["spread_seeds"]
    extra = [s for s in spread if s not in seeds]
    assert seeds == [0, 1, 2] and extra, "the cpu preset's spread seeds go beyond its seeds"
    home, n = config["homes"][0], 20
    results = tmp_path / "results" / "cpu"
    for height in (0.45, 1.05):
        scen = results / "scenarios" / home / "everywhere" / f"h{height:g}.csv"
        scen.parent.mkdir(parents=True, exist_ok=True)
        # the same draws at both heights: every scenario is a shared draw
        pd.DataFrame({"scenario_id": range(n), "layout": home, "placement": "everywhere", "height": height,
                      "start_x": [float(i) for i in range(n)], "start_y": 1.0, "start_theta": 0.0,
                      "target_object": "cereal_box", "target_x": 2.0, "target_y": 3.0,
                      "target_z": 0.45}).to_csv(scen, index=False)
        for seed in seeds + extra:
            # Table 1's seeds succeed in every episode at both heights; a spread seed fails at 1.05 m
            success = 0 if (seed in extra and height == 1.05) else 1
            path = results / "eval" / "head_on" / f"seed{seed}" / home / "everywhere" / scen.name
            path.parent.mkdir(parents=True, exist_ok=True)
            pd.DataFrame({"scenario_id": range(n), "success": success}).to_csv(path, index=False)
    res = table1_contrast(tmp_path, "cpu")((1.05, "everywhere"), (0.45, "everywhere"))
    assert res["n_seeds"] == len(seeds) and res["n_shared"] == n
    assert res["difference"] == 0.0 and res["ci_low"] == res["ci_high"] == 0.0
    # a preset with fewer seeds reads fewer of them (the smoke preset: seed 0)
    (tmp_path / "results" / "cpu").rename(tmp_path / "results" / "smoke")
    assert table1_contrast(tmp_path, "smoke")((1.05, "everywhere"), (0.45, "everywhere"))["n_seeds"] == 1


@needs_stored_run
def test_regenerate_reproduces_the_stored_cpu_tables_and_figure_data(tmp_path, monkeypatch):
    """`egosearch report regenerate` from the stored CSVs gives the numbers the DAG stored."""
    results = tmp_path / "results" / "cpu"
    copy_stored_cpu_results(results)
    # A generalisation group's evaluations sit beside Table 1's homes in eval/: Table 1, Figure 6 and
    # the path-length tables must not read them (nor ask the provenance about them).
    for who in ("head_on", "random"):
        cell = sorted((results / "eval" / who / "seed0" / "kitchen_living").rglob("h1.05.csv"))[0]
        group = results / "eval" / who / "seed0" / "some_generated_group" / cell.parent.name / cell.name
        group.parent.mkdir(parents=True)
        group.write_text(cell.read_text())
    monkeypatch.chdir(tmp_path)
    assert main(["report", "regenerate", "--preset", "cpu"]) == 0
    stored, again = REPO / "paper_figs" / "cpu", tmp_path / "paper_figs" / "cpu"
    names = ["table1.csv", "table1.md", "table2.md", "fig6.csv", "fig7.csv", "fig7_oracle.csv"]
    assert [n for n in names if not (stored / n).exists()] == []
    for name in names:
        assert (again / name).read_text() == (stored / name).read_text(), name
    from egosearch.report.readme import table1_contrast  # the reading's paired contrasts too

    assert table1_contrast(tmp_path, "cpu")((1.05, "everywhere"), (0.45, "everywhere"))["n_shared"] > 0


@needs_stored_run
def test_regenerate_writes_the_bytes_the_dag_stored(tmp_path, monkeypatch):
    """Every file `egosearch report regenerate` writes equals, byte for byte, the one the DAG stored:
    tables, figures (PNG and PDF) and the path-length CSVs, whose rows follow the order in which the
    DAG hands the reference searchers' files over (one ordering function serves both)."""
    results = tmp_path / "results" / "cpu"
    copy_stored_cpu_results(results)
    shutil.rmtree(results / "pathlength")  # what regenerate writes must be written, not left from the copy
    monkeypatch.chdir(tmp_path)
    assert main(["report", "regenerate", "--preset", "cpu"]) == 0
    written = sorted(p for folder in (tmp_path / "paper_figs" / "cpu", results / "pathlength")
                     for p in folder.rglob("*") if p.is_file())
    assert len(written) >= 20 and any(p.suffix == ".pdf" for p in written)
    differ = [str(p.relative_to(tmp_path)) for p in written
              if p.read_bytes() != (REPO / p.relative_to(tmp_path)).read_bytes()]
    assert differ == []


@needs_stored_run
def test_regenerate_leaves_the_file_times_of_unchanged_outputs(tmp_path, monkeypatch):
    """Rewritten with the same bytes, an output keeps its file time: Snakemake then sees nothing new, so
    `snakemake all` after `regenerate` on a fresh clone has nothing to do."""
    copy_stored_cpu_results(tmp_path / "results" / "cpu")
    shutil.copytree(REPO / "paper_figs" / "cpu", tmp_path / "paper_figs" / "cpu")
    monkeypatch.chdir(tmp_path)
    outputs = [p for folder in ("paper_figs/cpu", "results/cpu/pathlength") for p in (tmp_path / folder).rglob("*")
               if p.is_file()]
    for i, path in enumerate(outputs):  # distinct old times, so that a rewrite cannot pass for unchanged
        os.utime(path, ns=(1_000_000_000 * (1000 + i),) * 2)
    before = {p: p.stat().st_mtime_ns for p in outputs}
    assert main(["report", "regenerate", "--preset", "cpu"]) == 0
    assert [str(p) for p in outputs if p.stat().st_mtime_ns != before[p]] == []


@needs_stored_run
def test_regenerate_twice_gives_byte_identical_files(tmp_path, monkeypatch):
    """A second regenerate rewrites every output with the same bytes (PDFs included: no date stamped)."""
    copy_stored_cpu_results(tmp_path / "results" / "cpu")
    monkeypatch.chdir(tmp_path)
    figs = tmp_path / "paper_figs" / "cpu"
    assert main(["report", "regenerate", "--preset", "cpu"]) == 0
    first = {p.name: p.read_bytes() for p in sorted(figs.iterdir())}
    assert {"fig6.pdf", "fig7.pdf", "fig6.png", "table1.tex"} <= set(first)
    for p in figs.iterdir():    # a stale file left in place must not pass for a rewritten one
        p.unlink()
    assert main(["report", "regenerate", "--preset", "cpu"]) == 0
    second = {p.name: p.read_bytes() for p in sorted(figs.iterdir())}
    assert sorted(second) == sorted(first)
    assert [name for name in first if first[name] != second[name]] == []


@needs_stored_run
def test_regenerate_refuses_a_stored_csv_edited_after_its_provenance(tmp_path, monkeypatch, capsys):
    from egosearch.report.provenance import write_provenance

    results = tmp_path / "results" / "cpu"
    copy_stored_cpu_results(results)
    monkeypatch.chdir(tmp_path)
    write_provenance("cpu", results, results / "provenance.json")
    assert main(["report", "verify", "--preset", "cpu"]) == 0
    stored = sorted((results / "eval" / "head_on").rglob("h1.05.csv"))[0]
    text = stored.read_text()
    stored.write_text(text[: len(text) // 3])
    capsys.readouterr()
    assert main(["report", "regenerate", "--preset", "cpu"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{stored.relative_to(tmp_path)} was truncated" in err
    assert not (tmp_path / "paper_figs").exists()          # refused before writing anything
    assert main(["report", "verify", "--preset", "cpu"]) == 2
