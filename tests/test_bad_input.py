"""Bad input as a new user types it: each is exactly one line naming what is wrong, before any
work starts, and never a traceback. The cases are the README's bad-input table."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import torch

from egosearch.cli import main
from egosearch.variants import VariantError, load_variant, new_variant, variant_names
from egosearch.workflow.check import ConfigError, check_config, checked_variants, coerce_numbers

REPO = Path(__file__).resolve().parent.parent
HEAD = "name: NAME\nenv_id: EgoSearch-v0\ntrain_env: {layout: kitchen_living, placement: everywhere}\n"
ALLOWED = ", ".join(variant_names(REPO / "ablations"))
# Snakemake's own notices, printed before the Snakefile body runs: the workflow profile, and
# --config on top of the config file.
NOTICES = ("Using workflow specific profile profiles/default for setting default command line arguments.",
           "Config file egosearch/workflow/config.yaml is extended by additional config specified via the command "
           "line.")

# (file stem, file text, the one line). Each is a typo the DAG used to pass, or a message that was
# a traceback.
BAD_VARIANT_FILES = [
    ("lr_typo", HEAD + "config: {critic_lrr: 0.0005}\n",
     "ablations/lr_typo.yaml: config: 'critic_lrr' is not a LearnerConfig field (did you mean critic_lr?)"),
    ("lr_word", HEAD + "config: {critic_lr: fast}\n",
     "ablations/lr_word.yaml: config: critic_lr='fast' is not a float"),
    ("lr_negative", HEAD + "config: {critic_lr: -1.0}\n",
     "ablations/lr_negative.yaml: config (on the cpu learner profile): LearnerConfig.critic_lr=-1.0 is out of "
     "range; allowed: > 0"),
    ("too_short", HEAD + "config: {train_height_min: 0.1}\n",
     "ablations/too_short.yaml: config (on the cpu learner profile): LearnerConfig.train_height_min=0.1 is out "
     "of range; allowed: [0.3, 1.8] m (training heights are drawn from [this, 1.8] m)"),
    ("steps_float", HEAD + "config: {total_env_steps: 2.5e4}\n",
     "ablations/steps_float.yaml: config: total_env_steps='2.5e4' is not an int"),
    ("steps_below_warmup", HEAD + "config: {total_env_steps: 500}\n",
     "ablations/steps_below_warmup.yaml: config (on the cpu learner profile): LearnerConfig.total_env_steps=500 is "
     "out of range; allowed: >= 4000, the env step of the first update (after init_steps=4000 random steps, an "
     "update every 4 steps): fewer train no update"),
    ("flag_word", HEAD + "config: {encoder_tanh: maybe}\n",
     "ablations/flag_word.yaml: config: encoder_tanh='maybe' is not a bool"),
    ("config_list", HEAD + "config: [1, 2]\n",
     "ablations/config_list.yaml: config: [1, 2] is not of type 'object'"),
    ("wrong_name", HEAD.replace("NAME", "head_on"),
     "ablations/wrong_name.yaml: name='head_on' must equal the file name 'wrong_name'"),
    ("object_typo", HEAD.replace("everywhere}", "everywhere, objects: [mug, spoon]}"),
     "ablations/object_typo.yaml: train_env/objects: 'spoon' unknown; allowed: book, cereal_box, duck, glasses_case, "
     "keys, mug, mustard_bottle, phone, remote, soda_can, teddy"),
    ("bad_yaml", HEAD.replace("everywhere}", "everywhere"),
     "ablations/bad_yaml.yaml: not valid YAML at line 4 (expected ',' or '}', but got '<stream end>')"),
    ("no_placement", HEAD.replace(", placement: everywhere", ""),
     "ablations/no_placement.yaml: train_env: 'placement' is a required property"),
    ("key_typo", HEAD + "confgi: {}\n",
     "ablations/key_typo.yaml: (top level): Additional properties are not allowed ('confgi' was unexpected)"),
    ("env_typo", HEAD.replace("EgoSearch-v0", "EgoSearch-v1"),
     "ablations/env_typo.yaml: env_id: 'EgoSearch-v1' is not one of ['EgoSearch-v0', 'EgoSearchNoHead-v0', "
     "'EgoSearchMemory-v0', 'EgoSearchNoHeadMemory-v0', 'EgoSearchMap-v0', 'EgoSearchNoHeadMap-v0']"),
    ("generated_no_split", HEAD.replace("layout: kitchen_living", "layout: generated"),
     "ablations/generated_no_split.yaml: train_env: layout: generated needs home_seeds: [first, stop)"),
    ("split_without_generated", HEAD.replace("everywhere}", "everywhere, home_seeds: [0, 10]}"),
     "ablations/split_without_generated.yaml: train_env: home_seeds is only read with layout: generated"),
    ("split_draws_heldout", HEAD.replace("layout: kitchen_living", "layout: generated, home_seeds: [899990, 900005]"),
     "ablations/split_draws_heldout.yaml: train_env: home_seeds=[899990, 900005) overlaps the held-out homes "
     "[900000, 900020) that no training may draw (egosearch.sim.home_pool.HELDOUT_HOME_SEEDS)"),
]

# (--config entries, the one line) of `snakemake -n all`.
BAD_CONFIGS = [
    (["variants=[head_on,hed_off]"], "variant='hed_off' is unknown; allowed: {allowed} (files in ablations)"),
    (["reference_variant=hed_on"], "variant='hed_on' is unknown; allowed: {allowed} (files in ablations)"),
    (["variant=nope"], "variant='nope' is unknown; allowed: {allowed} (files in ablations)"),
    (["heights=[7.0]"], "config heights/0: 7.0 is greater than the maximum of 2.0"),
    (["heights=[tall]"], "config heights/0: 'tall' is not of type 'number'"),
    (["profile=fast"], "config profile: 'fast' is not one of ['smoke', 'cpu', 'paper']"),
    (["placements=[under_the_sofa]"], "config placements/0: 'under_the_sofa' is not one of ['no_low_cabinets', "
                                      "'everywhere']"),
    (["scenario_seed=-1"], "config scenario_seed: -1 is less than the minimum of 0"),
    (["layout=mansion"], "config layout: 'mansion' does not match '^(kitchen_living|bedroom_bath|studio|home[0-9]+)$'"),
    (["heights=[1.05,1.05]"], "config heights: [1.05, 1.05] has non-unique elements"),
    (["homes=[kitchen_living,mansion]"], "config homes/1: 'mansion' does not match "
                                         "'^(kitchen_living|bedroom_bath|studio|home[0-9]+)$'"),
]


def config(**changes):
    import yaml

    base = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())
    return {**base, **changes}


@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    """The workflow files, its profiles and ablations/ with every bad variant file added (no results)."""
    dest = tmp_path_factory.mktemp("suite")
    shutil.copy2(REPO / "Snakefile", dest / "Snakefile")
    shutil.copytree(REPO / "egosearch" / "workflow", dest / "egosearch" / "workflow")
    shutil.copytree(REPO / "ablations", dest / "ablations")
    if (REPO / "profiles").is_dir():
        shutil.copytree(REPO / "profiles", dest / "profiles")
    for stem, text, _ in BAD_VARIANT_FILES:
        (dest / "ablations" / f"{stem}.yaml").write_text(text.replace("NAME", stem))
    return dest


def snakemake_lines(cwd, *args):
    out = subprocess.run([sys.executable, "-m", "snakemake", "-n", *args], cwd=cwd, capture_output=True, text=True,
                         timeout=600)
    lines = [line for line in (out.stdout + out.stderr).splitlines() if line.strip() and line not in NOTICES]
    return out.returncode, lines


@pytest.mark.parametrize("stem, text, message", BAD_VARIANT_FILES, ids=[c[0] for c in BAD_VARIANT_FILES])
def test_a_bad_variant_file_is_one_line_naming_the_field(suite, monkeypatch, capsys, stem, text, message):
    """What the Snakefile runs first (`checked_variants`): the one line on stderr, exit 1."""
    monkeypatch.chdir(suite)
    with pytest.raises(SystemExit) as stop:
        checked_variants(config(variant=stem), argv=["compare"], directory=suite / "ablations")
    assert stop.value.code == 1 and capsys.readouterr().err == f"egosearch: error: {message}\n"


@pytest.mark.parametrize("entries, message", BAD_CONFIGS, ids=[c[0][0] for c in BAD_CONFIGS])
def test_a_bad_config_is_one_line_naming_the_key(suite, monkeypatch, capsys, entries, message):
    monkeypatch.chdir(suite)
    # As Snakemake hands --config values over: list items as strings.
    changes = {}
    for entry in entries:
        key, value = entry.split("=", 1)
        changes[key] = value.strip("[]").split(",") if value.startswith("[") else int(value) if value.lstrip(
            "-").isdigit() else value
    with pytest.raises(SystemExit) as stop:
        checked_variants(config(**changes), argv=["all"], directory=suite / "ablations")
    allowed = ", ".join(variant_names(suite / "ablations"))
    assert stop.value.code == 1 and capsys.readouterr().err == f"egosearch: error: {message.format(allowed=allowed)}\n"


def test_a_generalise_reference_outside_its_variants_is_one_line(suite, monkeypatch, capsys):
    monkeypatch.chdir(suite)
    base = config()
    changed = {**base, "generalise": {**base["generalise"], "reference": "head_on_ppo"}}
    with pytest.raises(SystemExit) as stop:
        checked_variants(changed, argv=["generalise"], directory=suite / "ablations")
    assert stop.value.code == 1 and capsys.readouterr().err == (
        "egosearch: error: config generalise/reference: 'head_on_ppo' must be one of generalise/variants\n")


# Snakemake itself, on a few of them: its first line after its own --config notice is the message
# (a Snakemake run costs seconds, so the rest go through `checked_variants` above).
def test_snakemake_stops_on_a_variant_typo_before_the_dag(suite):
    rc, lines = snakemake_lines(suite, "compare", "--config", "variant=lr_typo")
    assert rc == 1 and lines == [f"egosearch: error: {BAD_VARIANT_FILES[0][2]}"]


def test_snakemake_stops_on_a_bad_config_with_one_line(suite):
    rc, lines = snakemake_lines(suite, "all", "--config", "heights=[7.0]")
    assert rc == 1 and lines == ["egosearch: error: config heights/0: 7.0 is greater than the maximum of 2.0"]


def test_compare_without_a_variant_is_one_line(suite):
    rc, lines = snakemake_lines(suite, "compare")
    assert rc == 1 and lines == ["egosearch: error: compare needs a variant: snakemake --cores 2 compare --config "
                                 "variant=NAME"]


def test_heights_given_on_the_command_line_are_numbers(suite):
    """`--config 'heights=[1.05]'` reaches Snakemake as ['1.05']: it is read as the number."""
    out = subprocess.run([sys.executable, "-m", "snakemake", "-n", "table1", "--config", "heights=[1.05]",
                          "profile=smoke"], cwd=suite, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    text = out.stdout + out.stderr
    assert "scenarios/kitchen_living/everywhere/h1.05.csv" in text
    assert "h1.65.csv" not in text and "h0.45.csv" not in text


def test_coerce_numbers_follows_the_schema():
    import json

    schema = json.loads((REPO / "egosearch/workflow/config.schema.json").read_text())
    cfg = config(heights=["1.05", "0.450"], scenario_seed="7", variants=["head_on", "12"],
                 profiles={**config()["profiles"], "smoke": {**config()["profiles"]["smoke"], "seeds": ["0", "3"]}})
    out = coerce_numbers(cfg, schema)
    assert out["heights"] == [1.05, 0.45] and out["scenario_seed"] == 7
    assert out["profiles"]["smoke"]["seeds"] == [0, 3]
    assert out["variants"] == ["head_on", "12"]  # strings where the schema wants strings
    bad = config(scenario_seed="7.5")
    with pytest.raises(ConfigError, match="config scenario_seed: '7.5' is not of type 'integer'"):
        check_config(bad)


def test_yaml_exponent_without_a_dot_is_a_float(tmp_path):
    """PyYAML reads `1e-4` as a string; a float field takes it as the number it spells."""
    (tmp_path / "lr.yaml").write_text(HEAD.replace("NAME", "lr") + "config: {critic_lr: 1e-4, batch_size: 64}\n")
    assert load_variant("lr", tmp_path).config == {"critic_lr": 1e-4, "batch_size": 64}


def test_variant_new_copies_the_template_with_its_name(tmp_path, monkeypatch):
    for name in ("head_on", "head_off"):
        shutil.copy2(REPO / "ablations" / f"{name}.yaml", tmp_path)
    made = load_variant(new_variant("my_variant", "head_off", tmp_path), tmp_path)
    base = load_variant("head_off", tmp_path)
    assert made.name == "my_variant" and made.path.endswith("my_variant.yaml")
    assert (made.env_id, made.train_env, made.config) == (base.env_id, base.train_env, base.config)
    with pytest.raises(VariantError, match="exists already"):
        new_variant("my_variant", directory=tmp_path)
    with pytest.raises(VariantError, match="letters, digits"):
        new_variant("my variant", directory=tmp_path)


def cli_error(capsys, *argv):
    assert main(list(argv)) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if not line.startswith("pybullet build time")]
    assert len(lines) == 1, err
    return lines[0]


def test_cli_bad_input_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(REPO)
    readme = REPO / "README.md"
    not_torch = tmp_path / "x.pt"
    torch.save({"a": 1}, not_torch)
    cases = [
        (["evaluate", "--scenarios", "s.csv", "--weights", str(readme), "--out", "o.csv"],
         f"egosearch evaluate: error: {readme} is not an egosearch actor file; an actor file is the actor.pt that "
         "`egosearch train` writes (results/<profile>/train/<variant>/seed<N>/actor.pt) (torch cannot read it: "
         "UnpicklingError)"),
        (["evaluate", "--scenarios", "s.csv", "--weights", str(not_torch), "--out", "o.csv"],
         f"egosearch evaluate: error: {not_torch} is not an egosearch actor file; an actor file is the actor.pt "
         "that `egosearch train` writes (results/<profile>/train/<variant>/seed<N>/actor.pt)"),
        (["evaluate", "--scenarios", "s.csv", "--weights", "missing.pt", "--out", "o.csv"],
         "egosearch evaluate: error: missing.pt: no such actor file"),
        (["evaluate", "--scenarios", "s.csv", "--policy", "banana", "--out", "o.csv"],
         "egosearch evaluate: error: --policy='banana'; allowed: oracle, random, frontier, frontier_head_off, actor"),
        (["evaluate", "--scenarios", "s.csv", "--policy", "random", "--env-id", "Foo-v0", "--out", "o.csv"],
         "egosearch evaluate: error: --env-id='Foo-v0'; allowed: EgoSearch-v0, EgoSearchNoHead-v0, "
         "EgoSearchMemory-v0, EgoSearchNoHeadMemory-v0, EgoSearchMap-v0, EgoSearchNoHeadMap-v0"),
        (["evaluate", "--scenarios", "s.csv", "--policy", "oracle", "--out", "o.csv"],
         "egosearch evaluate: error: s.csv: no such scenario file"),
        (["train", "--variant", "hed_on", "--out-dir", str(tmp_path / "run")],
         f"egosearch train: error: variant='hed_on' is unknown; allowed: {ALLOWED} (files in ablations)"),
        (["train", "--variant", "head_on", "--profile", "fast", "--out-dir", str(tmp_path / "run")],
         "egosearch train: error: unknown profile 'fast'; allowed: smoke, cpu, paper"),
        (["train", "--variant", "head_on", "--max-wall-s", "0", "--out-dir", str(tmp_path / "run")],
         "egosearch train: error: --max-wall-s must be a positive number of seconds, got 0.0"),
        (["bench", "gpu", "--seconds", "60"],
         "egosearch bench: error: bench gpu needs --out-dir (the paper-profile training's folder)"),
        (["bench", "gpu", "--seconds", "-1", "--out-dir", str(tmp_path / "run")],
         "egosearch bench: error: --seconds must be a positive number, got -1.0"),
        (["bench", "gpu", "--out-dir", str(tmp_path / "run"), "--baseline-seconds", "-5"],
         "egosearch bench: error: --baseline-seconds must be a number >= 0, got -5.0"),
        (["scenarios", "--height", "7", "--out", str(tmp_path / "s.csv")],
         "egosearch scenarios: error: height=7.0 is outside the sensible range [0.3, 2.0] m"),
        (["scenarios", "--n", "0", "--out", str(tmp_path / "s.csv")],
         "egosearch scenarios: error: --n=0: a scenario set needs at least 1 scenario"),
        (["variant", "new", "head_on"],
         "egosearch variant: error: ablations/head_on.yaml exists already; edit it, or choose another name"),
        (["variant", "check", "hed_on"],
         f"egosearch variant: error: variant='hed_on' is unknown; allowed: {ALLOWED} (files in ablations)"),
        (["report", "regenerate", "--profile", "fast"],
         "egosearch report: error: --profile='fast'; allowed: smoke, cpu, paper"),
        (["report", "fig6", str(tmp_path / "curve.csv"), "--out-prefix", str(tmp_path / "f6")],
         f"egosearch report: error: training curve CSV not found: {tmp_path / 'curve.csv'}"),
    ]
    for argv, message in cases:
        assert cli_error(capsys, *argv) == message, argv
    assert not (tmp_path / "run").exists() and not (tmp_path / "s.csv").exists()


def test_every_option_has_help():
    import argparse

    from egosearch.cli import build_parser

    def walk(parser, path):
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            if isinstance(action, argparse._SubParsersAction):
                helped = {a.dest for a in action._choices_actions if a.help}
                for name, sub in action.choices.items():
                    assert name in helped, f"{path} {name}"
                    walk(sub, f"{path} {name}")
            else:
                assert action.help, f"{path} {action.option_strings or action.dest}"

    walk(build_parser(), "egosearch")


def test_report_subcommands_print_their_own_help(capsys):
    with pytest.raises(SystemExit):
        main(["report", "regenerate", "--help"])
    out = capsys.readouterr().out
    assert out.startswith("usage: egosearch report regenerate") and "--planner" not in out and "--variant" in out


# --------------------------------------------------------------------------- output paths, before any work
@pytest.fixture
def no_work(monkeypatch):
    """Episodes, training and scenario generation fail the test: a bad output path must be refused first."""
    import egosearch.rl.train
    import egosearch.runs.evaluate
    import egosearch.sim.scenarios

    def work(*args, **kwargs):
        raise AssertionError("work started before the output paths were checked")

    for module, name in ((egosearch.runs.evaluate, "evaluate"), (egosearch.rl.train, "train"),
                         (egosearch.sim.scenarios, "generate_scenarios")):
        monkeypatch.setattr(module, name, work)


def test_output_paths_are_checked_before_any_work(tmp_path, capsys, monkeypatch, no_work):
    monkeypatch.chdir(REPO)
    folder, file = tmp_path / "a_folder", tmp_path / "a_file"
    folder.mkdir()
    file.write_text("x")
    under_file = f"{file}/sub/out.csv"
    is_folder = "is a folder; a file path is expected here"
    no_folder = f"{file} is a file, so no folder can be created under it"
    # The scenario file does not exist either: the output path is refused before it is read.
    evaluate = ["evaluate", "--scenarios", "missing.csv", "--policy", "oracle"]
    cases = [
        ([*evaluate, "--out", str(folder)], f"egosearch evaluate: error: --out={folder} {is_folder}"),
        ([*evaluate, "--out", under_file], f"egosearch evaluate: error: --out={under_file}: {no_folder}"),
        ([*evaluate, "--out", str(tmp_path / "o.csv"), "--traces", str(folder)],
         f"egosearch evaluate: error: --traces={folder} {is_folder}"),
        (["train", "--variant", "head_on", "--out-dir", str(file)],
         f"egosearch train: error: --out-dir={file} is a file; a folder is expected here"),
        (["train", "--variant", "head_on", "--out-dir", str(tmp_path / "run"), "--work-dir", f"{file}/partial"],
         f"egosearch train: error: --work-dir={file}/partial: {no_folder}"),
        (["scenarios", "--out", str(folder)], f"egosearch scenarios: error: --out={folder} {is_folder}"),
        (["fullbody", "--setting", "ours-M5-fetch", "--scenarios", "missing.csv", "--policy", "oracle", "--out",
          under_file], f"egosearch fullbody: error: --out={under_file}: {no_folder}"),
        (["video", "--scenarios", "missing.csv", "--policy", "oracle", "--out", str(tmp_path / "v.mp4"), "--still",
          str(folder)], f"egosearch video: error: --still={folder} {is_folder}"),
        (["report", "table1", "missing.csv", "--out-prefix", f"{file}/table1"],
         f"egosearch report: error: --out-prefix={file}/table1: {no_folder}"),
        (["report", "compare", "--reference", "a.csv", "--candidate", "b.csv", "--out", str(folder)],
         f"egosearch report: error: --out={folder} {is_folder}"),
        (["report", "provenance", "--results", str(tmp_path), "--out", str(folder)],
         f"egosearch report: error: --out={folder} {is_folder}"),
        (["report", "searches", "missing.npz", "--out-dir", str(file)],
         f"egosearch report: error: --out-dir={file} is a file; a folder is expected here"),
        (["pictures", "--out-dir", str(file)], f"egosearch pictures: error: --out-dir={file} is a file; a folder is "
                                               "expected here"),
    ]
    for argv, message in cases:
        assert cli_error(capsys, *argv) == message, argv
    # nothing written: no half file, no .tmp, no probe, no folder made for a refused run
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file", "a_folder"] and not list(folder.iterdir())


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs /proc (a location nobody may write in)")
def test_an_output_where_nothing_can_be_written_is_one_line(capsys, no_work):
    # /proc refuses new files even to root, for whom a chmod-ed folder is writable
    assert cli_error(capsys, "evaluate", "--scenarios", "missing.csv", "--policy", "oracle", "--out",
                     "/proc/egosearch/out.csv").startswith(
        "egosearch evaluate: error: --out=/proc/egosearch/out.csv: cannot write in /proc (")


def test_a_failed_csv_write_leaves_no_tmp(tmp_path):
    from egosearch.core.csvio import write_csv_atomic

    (tmp_path / "out.csv").mkdir()
    with pytest.raises(IsADirectoryError):
        write_csv_atomic(tmp_path / "out.csv", ["a"], [{"a": 1}])
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


# --------------------------------------------------------------------------- nonsense that used to be scored
def test_nonsense_scenarios_are_one_line_before_any_episode(tmp_path, capsys, no_work):
    from dataclasses import replace

    from egosearch.sim.scenarios import read_scenarios, write_scenarios

    stored = read_scenarios(REPO / "results/cpu/scenarios/kitchen_living/everywhere/h1.05.csv")[:3]
    spoiled = {
        "far_start": [replace(stored[0], start_x=stored[0].start_x + 500), *stored[1:]],
        "negative_path": [stored[0], replace(stored[1], shortest_path=-2.0), stored[2]],
        "duplicate_ids": [stored[0], stored[1], replace(stored[2], scenario_id=stored[0].scenario_id)],
    }
    expected = {
        "far_start": f":2: start ({stored[0].start_x + 500:g}, {stored[0].start_y:g}) is outside the home "
                     "kitchen_living, whose floor spans x in [0, 11], y in [0, 8] m",
        "negative_path": ":3: shortest_path=-2.0 is negative; it is the length (m) of the shortest route to a "
                         "success, >= 0",
        "duplicate_ids": f":4: scenario_id={stored[0].scenario_id} repeats the id of line 2; every scenario of a "
                         "file needs its own id (episodes are seeded and joined by it)",
    }
    for name, scenarios in spoiled.items():
        path = tmp_path / f"{name}.csv"
        write_scenarios(path, scenarios)
        line = cli_error(capsys, "evaluate", "--scenarios", str(path), "--policy", "oracle", "--out",
                         str(tmp_path / "o.csv"))
        assert line == f"egosearch evaluate: error: {path}{expected[name]}", name
    assert not (tmp_path / "o.csv").exists()


def test_a_variant_compared_with_itself_is_one_line(tmp_path, capsys, suite, monkeypatch):
    files = [str(tmp_path / "eval/head_on/seed0/kitchen_living/everywhere" / f"h{h}.csv") for h in ("0.45", "1.05")]
    assert cli_error(capsys, "report", "compare", "--reference", *files, "--candidate", *files, "--out",
                     str(tmp_path / "c.csv")) == (
        f"egosearch report: error: {files[0]} is both a reference and a candidate file (1 more file(s) too): "
        "compare two different variants (is the candidate the reference itself?)")
    assert not (tmp_path / "c.csv").exists()
    # and the workflow's `compare` target, before its DAG
    monkeypatch.chdir(suite)
    with pytest.raises(SystemExit):
        checked_variants(config(variant="head_on"), argv=["compare"], directory=suite / "ablations")
    assert capsys.readouterr().err == ("egosearch: error: variant='head_on' is the reference variant itself: compare "
                                       "needs another variant (or another reference_variant)\n")


def _actor_file(path: Path, action_dim: int, metadata: dict) -> Path:
    from egosearch.rl.config import load_config
    from egosearch.rl.registry import make_agent

    agent = make_agent(load_config("smoke", {"device": "cpu"}), action_dim, 30, 4, torch.device("cpu"))
    torch.save(agent.actor_state(metadata), path)
    return path


def test_an_actor_in_the_wrong_env_is_one_line_naming_its_env(tmp_path, capsys, no_work):
    """A head_off actor (3 action values) in EgoSearch-v0 (5) failed only in the first step, with numpy's
    broadcasting error; its file records the env id, or the sizes tell it."""
    from egosearch.rl.actor import ActorPolicy

    recorded = _actor_file(tmp_path / "recorded.pt", 3, {"variant": "head_off", "env_id": "EgoSearchNoHead-v0"})
    unrecorded = _actor_file(tmp_path / "unrecorded.pt", 3, {})
    assert ActorPolicy(unrecorded).trained_env_id() == "EgoSearchNoHead-v0"
    for path in (recorded, unrecorded):
        line = cli_error(capsys, "evaluate", "--scenarios", "missing.csv", "--weights", str(path), "--env-id",
                         "EgoSearch-v0", "--out", str(tmp_path / "o.csv"))
        assert line == (f"egosearch evaluate: error: {path}: this actor was trained in EgoSearchNoHead-v0 (3 action "
                        "values, 34 observation values besides depth), not in EgoSearch-v0 (5 and 34): run it in "
                        "EgoSearchNoHead-v0")
    # without --env-id an actor whose file names no env id acts in the one its sizes fit (it got EgoSearch-v0)
    assert cli_error(capsys, "evaluate", "--scenarios", "missing.csv", "--weights", str(unrecorded), "--out",
                     str(tmp_path / "o.csv")) == "egosearch evaluate: error: missing.csv: no such scenario file"


def test_the_sizes_an_actor_is_checked_against_are_the_envs():
    import gymnasium

    from egosearch.sim.envs import env_space_dims

    env = gymnasium.make("EgoSearchNoHeadMap-v0")
    try:
        space = env.observation_space
        assert env_space_dims("EgoSearchNoHeadMap-v0") == {
            "action": env.action_space.shape[0], "mask": space["mask"].shape[0], "proprio": space["proprio"].shape[0]}
    finally:
        env.close()
