"""The learner preset's word (issue 72): "preset" everywhere a user types it, the old "profile" still read with a
note for one release, and the records written before the rename still read as they are."""

from __future__ import annotations

import json
from pathlib import Path

from egosearch.cli import main
from egosearch.cli.parsers import OLD_PRESET_NOTE
from egosearch.core.preset_word import recorded_preset, with_preset_wildcard
from egosearch.cost.run_log import read_run_log
from egosearch.workflow.check import renamed_preset_key


def test_the_old_flag_is_the_new_one_with_a_note(capsys):
    assert main(["config", "show", "sac_drq", "--preset", "smoke"]) == 0
    new = capsys.readouterr()
    assert main(["config", "show", "sac_drq", "--profile", "smoke"]) == 0
    old = capsys.readouterr()
    assert old.out == new.out and "at preset smoke" in new.out.splitlines()[0]
    assert OLD_PRESET_NOTE not in new.err and old.err.splitlines() == [OLD_PRESET_NOTE]
    assert main(["config", "show", "sac_drq", "--profile=cpu"]) == 0  # the = spelling too
    assert capsys.readouterr().err.splitlines() == [OLD_PRESET_NOTE]


def test_the_old_flag_is_checked_as_the_new_one(capsys):
    assert main(["report", "regenerate", "--profile", "fast"]) == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        "egosearch report: error: --preset='fast'; allowed: smoke, cpu, paper")


def test_the_old_config_key_is_read_as_the_preset(capsys):
    config = {"preset": "cpu", "profile": "smoke", "variants": ["head_on"]}
    renamed_preset_key(config)
    assert config == {"preset": "smoke", "variants": ["head_on"]}
    assert "--config profile=NAME is the old name of --config preset=NAME" in capsys.readouterr().err
    config = {"preset": "cpu"}
    renamed_preset_key(config)
    assert config == {"preset": "cpu"} and capsys.readouterr().err == ""
    renamed_preset_key(quiet := {"profile": "paper"}, note=False)  # a job's own parse prints nothing
    assert quiet == {"preset": "paper"} and capsys.readouterr().err == ""


def test_records_written_before_the_rename_name_their_preset():
    assert recorded_preset({"profile": "cpu", "jobs": []}) == "cpu"
    assert recorded_preset({"preset": "paper"}) == "paper"
    assert recorded_preset({"jobs": []}) is None
    assert list(with_preset_wildcard({"profile": "cpu", "variant": "v", "seed": "0"})) == ["preset", "variant", "seed"]


def test_a_stored_log_of_the_old_word_reads_its_preset(tmp_path):
    log = tmp_path / "old.snakemake.log"
    log.write_text("\n".join([
        "[Mon Dec  7 10:00:00 2026]", "localrule train:", "    jobid: 3",
        "    wildcards: profile=cpu, variant=head_on, seed=0", "[Mon Dec  7 10:30:00 2026]",
        "Finished jobid: 3 (Rule: train)", ""]))
    (job,) = read_run_log(log).finished()
    assert job.wildcards == {"preset": "cpu", "variant": "head_on", "seed": "0"}


def test_the_stored_provenance_names_its_preset_in_either_spelling():
    """The stored cpu run's record is never rewritten for the rename: whichever word it was written with, it reads."""
    record = json.loads((Path(__file__).parents[1] / "results/cpu/provenance.json").read_text(encoding="utf-8"))
    assert recorded_preset(record) == "cpu"
