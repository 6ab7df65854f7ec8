"""Bad input as a new user types it: each is exactly one line naming what is wrong, before any
work starts, and never a traceback. The cases are the README's bad-input table."""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import torch

from egosearch.cli import main
from egosearch.searchers import searcher_registry as searchers
from egosearch.variants import VariantError, load_variant, new_variant, variant_names
from egosearch.workflow.check import ConfigError, check_config, checked_variants, coerce_numbers

TAKEN = ", ".join(searchers.names())
"""The registered searchers' names, as the error lines list them (a searcher registered later joins them)."""
BOUNDS = ", ".join(searchers.bounds())
"""The registered Table 1 bounds, in their table order, as the error lines list them."""

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
     "ablations/lr_negative.yaml: config (on the cpu learner preset): LearnerConfig.critic_lr=-1.0 is out of "
     "range; allowed: > 0"),
    ("too_short", HEAD + "config: {train_height_min: 0.1}\n",
     "ablations/too_short.yaml: config (on the cpu learner preset): LearnerConfig.train_height_min=0.1 is out "
     "of range; allowed: [0.3, 1.8] m (training heights are drawn from [this, 1.8] m)"),
    ("steps_float", HEAD + "config: {total_env_steps: 2.5e4}\n",
     "ablations/steps_float.yaml: config: total_env_steps='2.5e4' is not an int"),
    ("steps_below_warmup", HEAD + "config: {total_env_steps: 500}\n",
     "ablations/steps_below_warmup.yaml: config (on the cpu learner preset): LearnerConfig.total_env_steps=500 is "
     "out of range; allowed: >= 4000, the env step of the first update (after init_steps=4000 random steps, an "
     "update every 4 steps): fewer train no update"),
    ("cloning_without_teacher", HEAD + "config: {demo_episodes: 0}\n",
     "ablations/cloning_without_teacher.yaml: config (on the cpu learner preset): LearnerConfig.bc_updates=12000 "
     "is out of range; allowed: 0 unless demo_episodes >= 1 (it reads the demonstrations); without demonstrations "
     "set bc_updates: 0, critic_warmup_updates: 0, demo_batch_fraction: 0, bc_weight: 0, bc_decay_steps: 0, "
     "demo_teacher: frontier"),
    ("half_batches_all_demos", HEAD + "config: {demo_episodes: 100, demo_batch_fraction: 1.0}\n",
     "ablations/half_batches_all_demos.yaml: config (on the cpu learner preset): "
     "LearnerConfig.demo_batch_fraction=1.0 is out of range; allowed: [0, 1) (the rest of each batch is online)"),
    ("flag_word", HEAD + "config: {encoder_tanh: maybe}\n",
     "ablations/flag_word.yaml: config: encoder_tanh='maybe' is not a bool"),
    ("config_list", HEAD + "config: [1, 2]\n",
     "ablations/config_list.yaml: config: [1, 2] is not of type 'object'"),
    ("wrong_name", HEAD.replace("NAME", "head_on"),
     "ablations/wrong_name.yaml: name='head_on' must equal the file name 'wrong_name'"),
    ("modular_random", HEAD,
     "ablations/modular_random.yaml: name='modular_random' is a reference searcher's, whose evaluations sit in the "
     "same folders: name the variant otherwise (taken: " + TAKEN + ")"),
    ("object_typo", HEAD.replace("everywhere}", "everywhere, objects: [mug, spoon]}"),
     "ablations/object_typo.yaml: train_env/objects: 'spoon' unknown; allowed: book, cereal_box, duck, glasses_case, "
     "keys, mug, mustard_bottle, phone, remote, soda_can, teddy"),
    ("bad_yaml", HEAD.replace("everywhere}", "everywhere"),
     "ablations/bad_yaml.yaml: not valid YAML at line 4 (expected ',' or '}', but got '<stream end>')"),
    ("no_placement", HEAD.replace(", placement: everywhere", ""),
     "ablations/no_placement.yaml: train_env: 'placement' is a required property"),
    ("key_typo", HEAD + "confgi: {}\n",
     "ablations/key_typo.yaml: (top level): 'confgi' (did you mean 'config'?) is not a key here; allowed: name, "
     "description, env_id, train_env, config"),
    ("env_typo", HEAD.replace("EgoSearch-v0", "EgoSearch-v1"),
     "ablations/env_typo.yaml: env_id: 'EgoSearch-v1' is not one of ['EgoSearch-v0', 'EgoSearchNoHead-v0', "
     "'EgoSearchMemory-v0', 'EgoSearchNoHeadMemory-v0', 'EgoSearchMap-v0', 'EgoSearchNoHeadMap-v0', "
     "'EgoSearchModular-v0', 'EgoSearchNoHeadModular-v0']"),
    ("generated_no_split", HEAD.replace("layout: kitchen_living", "layout: generated"),
     "ablations/generated_no_split.yaml: train_env: layout: generated needs home_seeds: [first, stop)"),
    ("split_without_generated", HEAD.replace("everywhere}", "everywhere, home_seeds: [0, 10]}"),
     "ablations/split_without_generated.yaml: train_env: home_seeds is only read with layout: generated"),
    ("split_draws_heldout", HEAD.replace("layout: kitchen_living", "layout: generated, home_seeds: [899990, 900005]"),
     "ablations/split_draws_heldout.yaml: train_env: home_seeds=[899990, 900005) overlaps the held-out homes "
     "[900000, 900020) that no training may draw (egosearch.scene.layouts.HELDOUT_HOME_SEEDS)"),
]

# (--config entries, the one line) of `snakemake -n all`.
BAD_CONFIGS = [
    (["variants=[head_on,hed_off]"], "config variants: variant='hed_off' is unknown (did you mean 'head_off'?); "
                                     "allowed: {allowed} (files in ablations)"),
    (["reference_variant=hed_on"], "config reference_variant: variant='hed_on' is unknown (did you mean "
                                   "'head_on'?); allowed: {allowed} (files in ablations)"),
    (["variant=nope"], "config variant: variant='nope' is unknown; allowed: {allowed} (files in ablations)"),
    (["heights=[7.0]"], "config heights/0: 7.0 is greater than the maximum of 2.0"),
    (["heights=[tall]"], "config heights/0: 'tall' is not of type 'number'"),
    (["preset=fast"], "config preset: 'fast' is not one of ['smoke', 'cpu', 'paper']"),
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
    """The workflow files, its presets and ablations/ with every bad variant file added (no results)."""
    dest = tmp_path_factory.mktemp("suite")
    shutil.copy2(REPO / "Snakefile", dest / "Snakefile")
    shutil.copytree(REPO / "egosearch" / "workflow", dest / "egosearch" / "workflow")
    shutil.copytree(REPO / "ablations", dest / "ablations")
    if (REPO / "profiles").is_dir():
        shutil.copytree(REPO / "profiles", dest / "profiles")
    for stem, text, _ in (BAD_VARIANT_FILES + [(stem, text, line) for stem, _, text, line in ISSUE57_VARIANT_FILES]
                          + [(stem, text, line) for stem, _, text, line in ISSUE73_VARIANT_FILES]):
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


@pytest.mark.parametrize("pairs, message", [
    ([["head_on", "head_on"]], "config claims_pairs: ['head_on', 'head_on'] is one searcher twice; a pair is [head "
                               "moving, head fixed]"),
    ([["head_on", "head_of"]], re.compile(r"config claims_pairs: variant='head_of' is unknown \(did you mean "
                                          r"'head_off'\?\); allowed: .*")),
    ([["head_on"]], re.compile(r"config claims_pairs/0: \['head_on'\] is too short")),
], ids=["one_searcher_twice", "variant_typo", "one_searcher"])
def test_a_bad_claims_pair_is_one_line(suite, monkeypatch, capsys, pairs, message):
    monkeypatch.chdir(suite)
    with pytest.raises(SystemExit) as stop:
        checked_variants(config(claims_pairs=pairs), argv=["behaviour"], directory=suite / "ablations")
    err = capsys.readouterr().err
    assert stop.value.code == 1 and err.count("\n") == 1 and err.startswith("egosearch: error: ")
    line = err.removeprefix("egosearch: error: ").rstrip("\n")
    assert message.fullmatch(line) if isinstance(message, re.Pattern) else line == message, line


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
                          "preset=smoke"], cwd=suite, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    text = out.stdout + out.stderr
    assert "scenarios/kitchen_living/everywhere/h1.05.csv" in text
    assert "h1.65.csv" not in text and "h0.45.csv" not in text


def test_coerce_numbers_follows_the_schema():
    import json

    schema = json.loads((REPO / "egosearch/workflow/config.schema.json").read_text())
    cfg = config(heights=["1.05", "0.450"], scenario_seed="7", variants=["head_on", "12"],
                 presets={**config()["presets"], "smoke": {**config()["presets"]["smoke"], "seeds": ["0", "3"]}})
    out = coerce_numbers(cfg, schema)
    assert out["heights"] == [1.05, 0.45] and out["scenario_seed"] == 7
    assert out["presets"]["smoke"]["seeds"] == [0, 3]
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


def test_variant_new_says_to_screen_first_as_the_ablations_page_does(tmp_path, monkeypatch, capsys):
    import egosearch.cli.variant

    shutil.copy2(REPO / "ablations" / "head_on.yaml", tmp_path)
    monkeypatch.setattr(egosearch.cli.variant, "ABLATIONS_DIR", tmp_path)
    assert main(["variant", "new", "my_lever"]) == 0
    said = capsys.readouterr().out
    screen, compare = ("snakemake --cores 2 screen --config variant=my_lever",
                       "snakemake --cores 2 compare --config variant=my_lever")
    assert (tmp_path / "my_lever.yaml").is_file() and said.index(screen) < said.index(compare)
    page = (REPO / "docs" / "ablations.md").read_text()
    assert page.index(screen.replace("my_lever", "my_variant")) < page.index(compare.replace("my_lever", "my_variant"))


@pytest.mark.parametrize("argv, hint", [
    (["generalise"], "'generalise' is not a command; it is `egosearch report generalise`, or the workflow's target "
                     "`snakemake --cores 2 generalise`"),
    (["fresh"], "'fresh' is not a command; it is `egosearch report fresh`, or the workflow's target "
                "`snakemake --cores 2 fresh`"),
    (["traces"], "'traces' is not a command: `egosearch evaluate --traces FILE.npz` writes a search's every step; "
                 "`egosearch report behaviour` and `egosearch report searches` read them (the workflow's targets: "
                 "`snakemake --cores 2 behaviour searches`)"),
    (["evalute", "--policy", "oracle"], "'evalute' is not a command; did you mean `egosearch evaluate`?"),
], ids=["generalise", "fresh", "traces", "evalute"])
def test_a_misplaced_command_gets_a_hint(argv, hint, capsys):
    assert main(argv) == 2
    assert capsys.readouterr().err == f"egosearch: error: {hint}\n"


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
         "`egosearch train` writes (results/<preset>/train/<variant>/seed<N>/actor.pt) (torch cannot read it: "
         "UnpicklingError)"),
        (["evaluate", "--scenarios", "s.csv", "--weights", str(not_torch), "--out", "o.csv"],
         f"egosearch evaluate: error: {not_torch} is not an egosearch actor file; an actor file is the actor.pt "
         "that `egosearch train` writes (results/<preset>/train/<variant>/seed<N>/actor.pt)"),
        (["evaluate", "--scenarios", "s.csv", "--weights", "missing.pt", "--out", "o.csv"],
         "egosearch evaluate: error: missing.pt: no such actor file"),
        (["evaluate", "--scenarios", "s.csv", "--policy", "banana", "--out", "o.csv"],
         "egosearch evaluate: error: --policy='banana'; allowed: " + TAKEN + ", actor"),
        (["evaluate", "--scenarios", "s.csv", "--policy", "modular_random", "--weights", "a.pt", "--out", "o.csv"],
         "egosearch evaluate: error: --weights=a.pt is only read with --policy actor, not --policy modular_random: "
         "drop one of them"),
        (["evaluate", "--scenarios", "s.csv", "--policy", "random", "--env-id", "Foo-v0", "--out", "o.csv"],
         "egosearch evaluate: error: --env-id='Foo-v0'; allowed: EgoSearch-v0, EgoSearchNoHead-v0, "
         "EgoSearchMemory-v0, EgoSearchNoHeadMemory-v0, EgoSearchMap-v0, EgoSearchNoHeadMap-v0, "
         "EgoSearchModular-v0, EgoSearchNoHeadModular-v0"),
        (["evaluate", "--scenarios", "s.csv", "--policy", "oracle", "--out", "o.csv"],
         "egosearch evaluate: error: s.csv: no such scenario file"),
        (["train", "--variant", "hed_on", "--out-dir", str(tmp_path / "run")],
         f"egosearch train: error: variant='hed_on' is unknown (did you mean 'head_on'?); allowed: {ALLOWED} (files in "
         "ablations)"),
        (["train", "--variant", "head_on", "--preset", "fast", "--out-dir", str(tmp_path / "run")],
         "egosearch train: error: unknown preset 'fast'; allowed: smoke, cpu, paper"),
        (["train", "--variant", "head_on", "--max-wall-s", "0", "--out-dir", str(tmp_path / "run")],
         "egosearch train: error: --max-wall-s must be a positive number of seconds, got 0.0"),
        (["demos", "--variant", "hed_on", "--episodes", "5", "--out", str(tmp_path / "d.replay.npz")],
         f"egosearch demos: error: variant='hed_on' is unknown (did you mean 'head_on'?); allowed: {ALLOWED} (files in "
         "ablations)"),
        (["demos", "--variant", "head_on", "--episodes", "0", "--out", str(tmp_path / "d.replay.npz")],
         "egosearch demos: error: --episodes=0: a number of episodes must be >= 1"),
        (["demos", "--variant", "head_on", "--episodes", "5", "--out", str(tmp_path / "d.npz")],
         f"egosearch demos: error: --out={tmp_path / 'd.npz'}: a demonstrations file (git-ignored: hundreds of MB) "
         "must end in .replay.npz"),
        (["bench", "gpu", "--seconds", "60"],
         "egosearch bench: error: bench gpu needs --out-dir (the paper-preset training's folder)"),
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
         f"egosearch variant: error: variant='hed_on' is unknown (did you mean 'head_on'?); allowed: {ALLOWED} "
         "(files in ablations)"),
        (["report", "regenerate", "--preset", "fast"],
         "egosearch report: error: --preset='fast'; allowed: smoke, cpu, paper"),
        (["report", "fig6", str(tmp_path / "curve.csv"), "--out-prefix", str(tmp_path / "f6")],
         f"egosearch report: error: the input files: {tmp_path / 'curve.csv'} not found"),
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
    Path(files[0]).parent.mkdir(parents=True)
    for file in files:
        shutil.copy2(REPO / "results/cpu" / Path(file).relative_to(tmp_path), file)
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
    from egosearch.rl.learner_registry import make_agent

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

    from egosearch.envs import env_space_dims

    env = gymnasium.make("EgoSearchNoHeadMap-v0")
    try:
        space = env.observation_space
        assert env_space_dims("EgoSearchNoHeadMap-v0") == {
            "action": env.action_space.shape[0], "mask": space["mask"].shape[0], "proprio": space["proprio"].shape[0]}
    finally:
        env.close()


# --------------------------------------------------------------------------- issue 35: the table of bad inputs
# Each bad input as a user typed it: (id, what it did before the fix, argv, the one line now). "before" is
# one of BEFORE_KINDS: clear (one line naming the option or file, before any work), cryptic (one line
# naming neither, or given only after work had started), traceback, silent (ran on: wrong results, an
# option ignored, or a file overwritten, without a word). {t} is the cases' folder (fixture `bad`).
# Expected lines that name how a file is known to be stored (git, or a provenance record where there
# is no git) are regular expressions.
BEFORE_KINDS = ("clear", "cryptic", "traceback", "silent")
S3 = "{t}/s3.csv"
EV = "{t}/eval/{v}/seed0/{home}/everywhere/h1.05.csv"
ev = lambda v, home="kitchen_living": EV.replace("{v}", v).replace("{home}", home)  # noqa: E731
TRACES = ["{t}/traces/head_on/seed0/kitchen_living/everywhere/h1.65.npz",
          "{t}/traces/head_off/seed0/kitchen_living/everywhere/h1.65.npz"]
GEN = [ev("head_on", "generated_heldout"), "--bounds", ev("random", "generated_heldout"),
       ev("oracle", "generated_heldout")]
CURVE, CELL = "{t}/train/head_on/seed0/curve.csv", "{t}/eval/head_on/seed0/kitchen_living/no_low_cabinets/h1.05.csv"
EMPTY_EVAL = "{t}/emptyeval/cand/seed0/kitchen_living/everywhere/h1.05.csv"
CHECKPOINT = ("egosearch train: error: --out-dir: {t}/run/done.json belongs to variant='head_on' "
              "env_id='EgoSearchMemory-v0', not variant={variant} env_id={env}; use another out_dir")
STORED = r"\((tracked by git|listed in the results' provenance\.json)[^)]*\)"

ISSUE_CASES = [
    # -- the issue's own cases (items 1 to 3 and 5)
    ("fullbody_limit_negative", "silent",
     ["fullbody", "--setting", "ours-M5-fetch", "--policy", "oracle", "--scenarios", S3, "--limit", "-1", "--out",
      "{t}/o.csv"],
     "egosearch fullbody: error: --limit=-1: the number of scenarios to use (0: all) must be >= 0"),
    ("target_z_25m", "silent", ["evaluate", "--scenarios", "{t}/zhigh.csv", "--policy", "oracle", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: {t}/zhigh.csv:3: target_z=25 is outside the home kitchen_living, whose height "
     "range is [0, 2.6] m (target_z: the height of the surface it rests on)"),
    ("shortest_path_edited", "silent",
     ["evaluate", "--scenarios", "{t}/ell.csv", "--policy", "oracle", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: {t}/ell.csv:4: shortest_path=0.3 is shorter than the straight line from the start "
     "to where the target is within reach (2.49 m); ℓ is >= that"),
    ("scenarios_n_huge", "silent", ["scenarios", "--n", "1000000000000", "--out", "{t}/s.csv"],
     "egosearch scenarios: error: --n=1000000000000: at most 10000 scenarios in one set (minutes at ~40 "
     "scenarios/s; a Table 1 cell has 200)"),
    ("scenarios_homes_huge", "silent", ["scenarios", "--homes", "0:100000000", "--out", "{t}/s.csv"],
     "egosearch scenarios: error: --homes=0:100000000: 100000000 homes; at most 1000 in one set"),
    ("scenarios_n_times_homes", "silent", ["scenarios", "--homes", "0:500", "--n", "100", "--out", "{t}/s.csv"],
     "egosearch scenarios: error: --n=100 per home x --homes=0:500 (500 homes) is 50000 scenarios; at most 10000 "
     "in one set"),
    ("weights_with_oracle", "silent",
     ["evaluate", "--scenarios", S3, "--policy", "oracle", "--weights", "{t}/x.pt", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: --weights={t}/x.pt is only read with --policy actor, not --policy oracle: drop one "
     "of them"),
    ("compare_smoke_candidate_cpu_reference", "silent",
     ["report", "compare", "--reference", "{t}/prof/results/cpu/eval/head_on/seed0/kitchen_living/everywhere/h1.05.csv",
      "--candidate", "{t}/prof/results/cpu/eval/cand/seed0/kitchen_living/everywhere/h1.05.csv"],
     "egosearch report: error: --candidate: {t}/prof/results/cpu/eval/cand/seed0/kitchen_living/everywhere/h1.05.csv "
     "was evaluated from an actor trained at the smoke learner preset "
     "({t}/prof/results/cpu/train/cand/seed0/config.json), the reference's at cpu: compare variants trained at one "
     "preset"),
    ("evaluate_threads_negative", "traceback",
     ["evaluate", "--scenarios", S3, "--policy", "oracle", "--threads", "-3", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: --threads=-3: a number of threads (0: all cores) must be >= 0"),
    ("train_into_another_variants_run", "traceback", ["train", "--variant", "head_off", "--out-dir", "{t}/run"],
     CHECKPOINT.format(t="{t}", variant="'head_off'", env="'EgoSearchNoHeadMemory-v0'")),
    ("train_into_a_run_of_another_preset", "traceback",
     ["train", "--variant", "head_on", "--preset", "smoke", "--out-dir", "{t}/run"],
     # at smoke head_on has its cpu learner and observation (issue 73): what differs is every size of the run
     "egosearch train: error: --out-dir: finished run {t}/run/done.json was written with a different config: "
     "actor_hidden_dim=256 (now 64), actor_snapshot_every=50000 (now 150), batch_size=64 (now 32), "
     "bc_decay_steps=100000 (now 150) ...; use another out_dir"),
    ("train_into_a_run_of_another_seed", "traceback", ["train", "--variant", "head_on", "--seed", "5", "--out-dir",
                                                       "{t}/run"],
     "egosearch train: error: --out-dir: finished run {t}/run/done.json was written with a different config: seed=0 "
     "(now 5); use another out_dir"),
    ("train_work_dir_beside_another_run", "silent",
     ["train", "--variant", "head_off", "--work-dir", "{t}/partial", "--out-dir", "{t}/run"],
     CHECKPOINT.format(t="{t}", variant="'head_off'", env="'EgoSearchNoHeadMemory-v0'")),
    ("scenarios_seed_negative", "cryptic", ["scenarios", "--seed", "-7", "--out", "{t}/s.csv"],
     "egosearch scenarios: error: --seed=-7: a seed must be >= 0"),
    ("binary_scenario_csv", "cryptic", ["evaluate", "--scenarios", "{t}/bin.csv", "--policy", "oracle", "--out",
                                        "{t}/o.csv"],
     "egosearch evaluate: error: {t}/bin.csv: not a text CSV file (byte 0x80 is not UTF-8 text); a scenario file "
     "is written by `egosearch scenarios`"),
    ("evaluate_seed_negative", "traceback",
     ["evaluate", "--scenarios", S3, "--policy", "oracle", "--seed", "-1", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: --seed=-1: a seed must be >= 0"),
    ("empty_variant_yaml", "cryptic", ["variant", "check", "{t}/empty.yaml"],
     "egosearch variant: error: {t}/empty.yaml: empty file; a variant needs name, env_id, train_env"),
    ("compare_empty_candidate", "cryptic", ["report", "compare", "--reference", ev("head_on"), "--candidate",
                                            EMPTY_EVAL],
     f"egosearch report: error: --candidate: {EMPTY_EVAL} is empty; a CSV file has a header line and rows"),
    ("compare_other_scenarios_same_ids", "silent",  # the CSV was written, then ℓ refused: the file stayed
     ["report", "compare", "--reference", "{t}/cmp/ref/seed0/kitchen_living/everywhere/h1.05.csv", "--candidate",
      "{t}/cmp/cand/seed0/kitchen_living/everywhere/h1.05.csv", "--out", "{t}/c.csv"],
     "egosearch report: error: compare: scenario 0 of kitchen_living/everywhere/h1.05.csv has ℓ 8.9812 in the "
     "reference and 9.9812 in the candidate: not the same scenarios"),
    ("video_out_txt", "cryptic", ["video", "--scenarios", S3, "--policy", "oracle", "--out", "{t}/x.txt", "--still",
                                  "{t}/x.png"],
     "egosearch video: error: --out={t}/x.txt: the video must end in .mp4 or .gif"),
    ("video_still_jpg", "silent", ["video", "--scenarios", S3, "--policy", "oracle", "--out", "{t}/x.gif", "--still",
                                   "{t}/x.jpg"],
     "egosearch video: error: --still={t}/x.jpg: the still must end in .png"),
    ("bench_frames_negative", "cryptic", ["bench", "env", "--frames", "-1"],
     "egosearch bench: error: --frames=-1: the number of sensor frames to time must be >= 1"),
    ("fullbody_M0", "cryptic", ["fullbody", "--setting", "ours-M0-fetch", "--policy", "oracle", "--scenarios", S3,
                                "--out", "{t}/o.csv"],
     "egosearch fullbody: error: --setting=ours-M0-fetch: M=0; M is the number of steps executed per plan, >= 1"),
    ("fullbody_T_negative", "cryptic", ["fullbody", "--setting", "ours-M5-fetch", "--policy", "oracle", "--scenarios",
                                        S3, "--T", "-1", "--out", "{t}/o.csv"],
     "egosearch fullbody: error: --T=-1: the planning horizon must be >= 1"),
    ("fullbody_M_above_T", "cryptic", ["fullbody", "--setting", "ours-M25-fetch", "--policy", "oracle", "--scenarios",
                                       S3, "--out", "{t}/o.csv"],
     "egosearch fullbody: error: --setting=ours-M25-fetch with --T=20: ours executes M=25 steps of each plan, more "
     "than the plan's T=20; allowed: M <= T"),
    ("evaluate_out_is_its_scenarios", "silent",
     ["evaluate", "--scenarios", "{t}/s3copy.csv", "--policy", "oracle", "--out", "{t}/s3copy.csv"],
     "egosearch evaluate: error: --out={t}/s3copy.csv is also an input (--scenarios): a command never writes over "
     "its own input; choose another output path"),
    ("bench_gpu_without_cuda", "silent", ["bench", "gpu", "--seconds", "5", "--out-dir", "{t}/gpu"],
     "egosearch bench: error: bench gpu needs a CUDA GPU, and torch {torch} sees none on this machine; "
     "`bench learner` times the learners on the CPU"),
    # -- stored results (item 1): run from the checkout's root, whose results/ and paper_figs/ are stored
    ("evaluate_out_stored", "silent",
     ["evaluate", "--scenarios", S3, "--policy", "oracle", "--out",
      "results/cpu/eval/oracle/seed0/kitchen_living/everywhere/h1.05.csv"],
     re.compile(r"egosearch evaluate: error: --out=results/cpu/eval/oracle/seed0/kitchen_living/everywhere/h1\.05\.csv "
                rf"is a stored result {STORED}; pass --force to overwrite it, or write elsewhere")),
    ("pictures_default_folder_stored", "silent", ["pictures"],
     re.compile(r"egosearch pictures: error: --out-dir=paper_figs/world holds stored results "
                r"\(paper_figs/world/kitchen_living_placements\.png, [^)]*\), which this command may overwrite; pass "
                r"--force to overwrite them, or write elsewhere")),
    ("bench_out_stored", "silent", ["bench", "learner", "--out", "results/cpu/bench/learner.json"],
     re.compile(rf"egosearch bench: error: --out=results/cpu/bench/learner\.json is a stored result {STORED}; pass "
                r"--force to overwrite it, or write elsewhere")),
    ("table1_prefix_stored", "silent",
     ["report", "table1", ev("head_on"), "--out-prefix", "paper_figs/cpu/table1"],
     re.compile(r"egosearch report: error: --out-prefix=paper_figs/cpu/table1 writes paper_figs/cpu/table1\.csv, which "
                rf"is a stored result {STORED}; pass --force to overwrite it, or write elsewhere")),
    ("provenance_out_stored", "silent", ["report", "provenance", "--out", "results/cpu/provenance.json"],
     re.compile(rf"egosearch report: error: --out=results/cpu/provenance\.json is a stored result {STORED}; pass "
                r"--force to overwrite it, or write elsewhere")),
    ("train_out_dir_stored", "traceback",
     ["train", "--variant", "head_on", "--out-dir", "results/cpu/train/head_on/seed0"],
     re.compile(r"egosearch train: error: --out-dir=results/cpu/train/head_on/seed0 holds stored results "
                r"\(results/cpu/train/head_on/seed0/[a-z_]+\.[a-z]+, [^)]*\), which this command may overwrite; pass "
                r"--force to overwrite them, or write elsewhere")),
]

# The 33 new bad inputs tried in the recently added commands (issue 35, item 5).
NEW_CASES = [
    ("generalise_trained_on_without_equals", "silent", ["report", "generalise", *GEN, "--trained-on", "head_on",
                                                        "--out-prefix", "{t}/g"],
     "egosearch report: error: --trained-on 'head_on': expected VARIANT=HOMES (e.g. head_on=paper_homes)"),
    ("generalise_generated_not_a_policy", "silent", ["report", "generalise", *GEN, "--generated", "nope",
                                                     "--out-prefix", "{t}/g"],
     "egosearch report: error: --generated='nope' is none of the files' variants (head_on): its rows would be left "
     "out without a word"),
    ("generalise_reference_not_a_policy", "silent", ["report", "generalise", *GEN, "--generated", "head_on",
                                                     "--reference", "nope", "--out-prefix", "{t}/g"],
     "egosearch report: error: --reference='nope' is none of the files' variants (head_on): its rows would be left "
     "out without a word"),
    ("generalise_empty_policy_csv", "cryptic", ["report", "generalise", EMPTY_EVAL, *GEN[1:], "--out-prefix", "{t}/g"],
     f"egosearch report: error: the input files: {EMPTY_EVAL} is empty; a CSV file has a header line and rows"),
    ("generalise_prefix_overwrites_an_input", "silent",
     ["report", "generalise", "{t}/g_in/head_on/seed0/generated_heldout/everywhere/h1.05.csv", *GEN[1:],
      "--out-prefix", "{t}/g_in/head_on/seed0/generated_heldout/everywhere/h1.05"],
     "egosearch report: error: --out-prefix={t}/g_in/head_on/seed0/generated_heldout/everywhere/h1.05 writes "
     "{t}/g_in/head_on/seed0/generated_heldout/everywhere/h1.05.csv, which is also an input (the input files): a "
     "command never writes over its own input; choose another output path"),
    ("behaviour_pair_not_traced", "silent", ["report", "behaviour", *TRACES, "--pairs", "head_on:nope",
                                             "--out-prefix", "{t}/b"],
     "egosearch report: error: no trace files of nope (the pairs' variants); the files hold head_off, head_on"),
    ("behaviour_pair_of_one_searcher", "silent", ["report", "behaviour", *TRACES, "--pairs", "head_on:head_on",
                                                  "--out-prefix", "{t}/b"],
     "egosearch report: error: --pairs 'head_on:head_on': expected HEAD_ON:HEAD_OFF, two different searchers (e.g. "
     "head_on:head_off)"),
    ("behaviour_csv_named_npz", "cryptic",
     ["report", "behaviour", "{t}/badtraces/head_on/seed0/kitchen_living/everywhere/h1.65.npz", TRACES[1],
      "--out-prefix", "{t}/b"],
     "egosearch report: error: the input files: {t}/badtraces/head_on/seed0/kitchen_living/everywhere/h1.65.npz is "
     "not an .npz file (numpy's zip format); a trace file is written by `egosearch evaluate --traces`"),
    ("behaviour_empty_npz", "traceback",
     ["report", "behaviour", "{t}/zerotraces/head_on/seed0/kitchen_living/everywhere/h1.65.npz", TRACES[1],
      "--out-prefix", "{t}/b"],
     "egosearch report: error: the input files: {t}/zerotraces/head_on/seed0/kitchen_living/everywhere/h1.65.npz is "
     "empty; a trace file is written by `egosearch evaluate --traces`"),
    ("searches_seed_without_files", "silent", ["report", "searches", *TRACES, "--seed", "5", "--out-dir", "{t}/srch"],
     "egosearch report: error: --seed=5: no trace file of seed 5 among the files (their seeds: 0), so no search "
     "would be pictured"),
    ("searches_seed_negative", "silent", ["report", "searches", *TRACES, "--seed", "-1", "--out-dir", "{t}/srch"],
     "egosearch report: error: --seed=-1: a seed must be >= 0"),
    ("searches_unknown_home", "cryptic",
     ["report", "searches", "{t}/mansion/head_on/seed0/mansion/everywhere/h1.65.npz", "--out-dir", "{t}/srch"],
     "egosearch report: error: {t}/mansion/head_on/seed0/mansion/everywhere/h1.65.npz: the home 'mansion' of its "
     "path is unknown; allowed: kitchen_living, bedroom_bath, studio or home<seed>"),
    ("searches_csv_named_npz", "cryptic",
     ["report", "searches", "{t}/badtraces/head_on/seed0/kitchen_living/everywhere/h1.65.npz", "--out-dir",
      "{t}/srch"],
     "egosearch report: error: the input files: {t}/badtraces/head_on/seed0/kitchen_living/everywhere/h1.65.npz is "
     "not an .npz file (numpy's zip format); a trace file is written by `egosearch evaluate --traces`"),
    ("fresh_seed_negative", "silent", ["report", "fresh", "--stored", ev("head_on"), "--fresh",
                                       "{t}/fresh/head_on/seed0/kitchen_living/everywhere/h1.05.csv", "--fresh-seed",
                                       "-3", "--out-prefix", "{t}/f"],
     "egosearch report: error: --fresh-seed=-3: a scenario seed must be >= 0"),
    ("fresh_prefix_with_a_dot", "silent", ["report", "fresh", "--stored", ev("head_on"), "--fresh",
                                           "{t}/fresh/head_on/seed0/kitchen_living/everywhere/h1.05.csv",
                                           "--out-prefix", "{t}/fresh.v2"],
     "egosearch report: error: --out-prefix={t}/fresh.v2: fresh would write {t}/fresh.csv (it replaces what follows "
     "a dot in the name); use a prefix without a dot in its name"),
    ("fresh_same_files_both_sides", "silent", ["report", "fresh", "--stored", ev("head_on"), "--fresh", ev("head_on"),
                                               "--out-prefix", "{t}/f"],
     f"egosearch report: error: {ev('head_on')} is both a --stored and a --fresh file: the check reads evaluations "
     "on two different scenario sets"),
    ("fresh_empty_csv", "cryptic", ["report", "fresh", "--stored", ev("head_on"), "--fresh",
                                    "{t}/emptyfresh/head_on/seed0/kitchen_living/everywhere/h1.05.csv",
                                    "--out-prefix", "{t}/f"],
     "egosearch report: error: --fresh: {t}/emptyfresh/head_on/seed0/kitchen_living/everywhere/h1.05.csv is empty; "
     "a CSV file has a header line and rows"),
    ("bench_gpu_cuda_graph_without_cuda", "silent", ["bench", "gpu", "--cuda-graph", "--seconds", "5", "--out-dir",
                                                     "{t}/gpu"],
     "egosearch bench: error: bench gpu needs a CUDA GPU, and torch {torch} sees none on this machine; "
     "`bench learner` times the learners on the CPU"),
    ("bench_learner_with_a_gpu_option", "silent", ["bench", "learner", "--seconds", "5"],
     "egosearch bench: error: --seconds is read by `bench gpu` only, not by `bench learner`"),
    ("bench_env_frames_zero", "traceback", ["bench", "env", "--frames", "0", "--steps", "10"],
     "egosearch bench: error: --frames=0: the number of sensor frames to time must be >= 1"),
    ("bench_env_steps_negative", "cryptic", ["bench", "env", "--frames", "10", "--steps", "-5"],
     "egosearch bench: error: --steps=-5: the number of env steps to time must be >= 1"),
    ("variant_check_unknown_preset", "cryptic", ["variant", "check", "head_on", "--preset", "fast"],
     "egosearch variant: error: --preset='fast'; allowed: smoke, cpu, paper"),
    ("variant_check_binary_yaml", "cryptic", ["variant", "check", "{t}/bin.yaml"],
     "egosearch variant: error: {t}/bin.yaml: not a text file; a variant is a YAML file with name, env_id, "
     "train_env"),
    ("variant_new_from_unknown", "clear", ["variant", "new", "tmp_bad_input_x", "--from", "nope"],
     f"egosearch variant: error: --from: variant='nope' is unknown; allowed: {ALLOWED} (files in ablations)"),
    ("variant_new_from_empty_file", "cryptic", ["variant", "new", "tmp_bad_input_y", "--from", "{t}/empty.yaml"],
     "egosearch variant: error: --from: {t}/empty.yaml: empty file; a variant needs name, env_id, train_env"),
    ("traces_same_file_as_out", "silent", ["evaluate", "--scenarios", S3, "--policy", "oracle", "--out",
                                           "{t}/same.npz", "--traces", "{t}/same.npz"],
     "egosearch evaluate: error: --traces={t}/same.npz is also written by --out: give each output its own path"),
    ("traces_not_npz", "clear", ["evaluate", "--scenarios", S3, "--policy", "oracle", "--out", "{t}/o.csv",
                                 "--traces", "{t}/t.csv"],
     "egosearch evaluate: error: --traces={t}/t.csv: a trace file must end in .npz"),
    ("budget_chosen_not_a_setting", "silent", ["report", "budget", "--run", f"head_on={CURVE}:{CELL}", "--chosen",
                                               "nope", "--out-prefix", "{t}/u"],
     "egosearch report: error: --chosen='nope' is none of the --run settings (head_on)"),
    ("budget_empty_eval", "cryptic", ["report", "budget", "--run", f"head_on={CURVE}:{EMPTY_EVAL}", "--out-prefix",
                                      "{t}/u"],
     f"egosearch report: error: --run: {EMPTY_EVAL} is empty; a CSV file has a header line and rows"),
    ("budget_same_run_twice", "clear", ["report", "budget", "--run", f"head_on={CURVE}:{CELL}", "--run",
                                        f"head_on={CURVE}:{CELL}", "--out-prefix", "{t}/u"],
     f"egosearch report: error: --run 'head_on={CURVE}:{CELL}': that run is given twice; each --run is one seed's "
     "run"),
    ("pathlength_out_csv_is_an_input", "silent",
     ["report", "pathlength", "{t}/pl_in/head_on/seed0/kitchen_living/everywhere/h1.05.csv", "--scenarios",
      "{t}/scen/kitchen_living/everywhere/h1.05.csv", "--out-prefix", "{t}/p", "--out-csv",
      "{t}/pl_in/head_on/seed0/kitchen_living/everywhere/h1.05.csv"],
     "egosearch report: error: --out-csv={t}/pl_in/head_on/seed0/kitchen_living/everywhere/h1.05.csv is also an "
     "input (the input files): a command never writes over its own input; choose another output path"),
    ("pathlength_binary_scenarios", "cryptic",
     ["report", "pathlength", ev("head_on"), "--scenarios", "{t}/binscen/kitchen_living/everywhere/h1.05.csv",
      "--out-prefix", "{t}/p"],
     "egosearch report: error: --scenarios: {t}/binscen/kitchen_living/everywhere/h1.05.csv is not a text CSV file "
     "(byte 128 is not UTF-8)"),
    ("pathlength_empty_eval", "cryptic", ["report", "pathlength", EMPTY_EVAL, "--scenarios",
                                          "{t}/scen/kitchen_living/everywhere/h1.05.csv", "--out-prefix", "{t}/p"],
     f"egosearch report: error: the input files: {EMPTY_EVAL} is empty; a CSV file has a header line and rows"),
]

# --------------------------------------------------------------------------- issue 48: a newcomer's round
# The same form as issue 35's table, with one more kind before the fix: damage (a stored or input file
# changed or left behind). The rows of the issue first (item 1), then the 30 new bad inputs of item 4,
# tried in the estimate, the searchers' env options, the variant files' new fields and the commands above.
BEFORE_KINDS_48 = ("clear", "cryptic", "traceback", "silent", "damage")
RECORD = ("a provenance record is the JSON file `egosearch report provenance` writes "
          "(results/<preset>/provenance.json)")
BENCH = "a learner benchmark record is the JSON file `egosearch bench learner --out` writes"
SNAKEMAKE_LOG = "a Snakemake log is .snakemake/log/<date>.snakemake.log"
NOT_A_VARIANT = "a variant is a name (a file in ablations) or the path of an existing .yaml file"

ISSUE48_CASES = [
    ("estimate_check_record_not_json", "cryptic",
     ["estimate", "check", "--log", "{t}/cpu.log", "--record", "{t}/notjson.json"],
     "egosearch estimate: error: --record: {t}/notjson.json is not JSON (Expecting property name enclosed in double "
     f"quotes at line 1); {RECORD}"),
    ("estimate_all_bench_not_json", "cryptic", ["estimate", "all", "--from-bench", "--bench", "{t}/notjson.json"],
     "egosearch estimate: error: --bench: {t}/notjson.json is not JSON (Expecting property name enclosed in double "
     f"quotes at line 1); {BENCH}"),
    ("estimate_check_a_csv_as_log_and_record", "cryptic",
     ["estimate", "check", "--log", S3, "--record", S3],
     "egosearch estimate: error: --log: {t}/s3.csv: no finished job in it (a Snakemake run's log, "
     ".snakemake/log/*.snakemake.log, of a run that ran jobs)"),
    ("estimate_check_record_a_list", "traceback", ["estimate", "check", "--log", "{t}/cpu.log", "--record",
                                                   "{t}/list.json"],
     f"egosearch estimate: error: --record: {{t}}/list.json holds a JSON list, not an object; {RECORD}"),
    ("estimate_all_bench_a_list", "traceback", ["estimate", "all", "--bench", "{t}/list.json", "--rate", "19"],
     f"egosearch estimate: error: --bench: {{t}}/list.json holds a JSON list, not an object; {BENCH}"),
    ("estimate_check_no_such_target", "traceback",
     ["estimate", "check", "--log", "{t}/cpu.log", "--target", "no_such_rule"],
     "egosearch estimate: error: --target='no_such_rule' is not a rule of the workflow; the run's target, e.g. all, "
     "table1 or screen (`snakemake --list-target-rules` lists them)"),
    ("estimate_check_smoke_log_against_the_cpu_record", "silent", ["estimate", "check", "--log", "{t}/smoke.log"],
     "egosearch estimate: error: results/smoke/provenance.json not found: the jobs of {t}/smoke.log ran at the smoke "
     "preset, and the check judges them against that preset's recorded job times: give --record, a record of the "
     "smoke preset"),
    ("estimate_check_preset_ignored", "silent", ["estimate", "check", "--log", "{t}/cpu.log", "--preset", "paper"],
     "egosearch estimate: error: --preset=paper: the jobs of {t}/cpu.log ran at the cpu preset (their paths say "
     "so): leave --preset out, or give the log of a paper run"),
    ("evaluate_head_off_floor_in_a_head_on_env", "silent",
     ["evaluate", "--scenarios", S3, "--policy", "modular_random_head_off", "--env-id", "EgoSearch-v0", "--out",
      "{t}/o.csv"],
     "egosearch evaluate: error: --env-id=EgoSearch-v0 moves the head, and --policy modular_random_head_off is the "
     "searcher with the head fixed: its rows would be read under that name; leave --env-id out, or use --policy "
     "modular_random"),
    ("variant_new_named_as_a_reference_searcher", "silent", ["variant", "new", "frontier"],
     "egosearch variant: error: variant name 'frontier' is a reference searcher's, whose evaluations sit in the same "
     "folders: name the variant otherwise (taken: " + TAKEN + ")"),
    ("variant_check_a_missing_path", "cryptic", ["variant", "check", "{t}/missing.yaml"],
     f"egosearch variant: error: {{t}}/missing.yaml: no such file; {NOT_A_VARIANT}"),
    ("train_seed_beyond_32_bits", "cryptic",
     ["train", "--variant", "head_on", "--seed", "99999999999999999999", "--out-dir", "{t}/run2"],
     "egosearch train: error: --seed=99999999999999999999: a seed must be at most 2**32 - 1 = 4294967295 (numpy's "
     "global seed is 32-bit)"),
    ("compare_a_file_with_its_copy", "silent",
     ["report", "compare", "--reference", ev("head_on"), "--candidate",
      "{t}/copy/cand/seed0/kitchen_living/everywhere/h1.05.csv"],
     "egosearch report: error: --candidate: {t}/copy/cand/seed0/kitchen_living/everywhere/h1.05.csv has the same "
     f"content as the reference's {ev('head_on')} (a copy?): every difference would be 0; compare two different "
     "variants, or pass --force when they did give the same episodes"),
    ("compare_missing_reference", "cryptic", ["report", "compare", "--reference", "{t}/missing.csv", "--candidate",
                                              ev("head_off")],
     "egosearch report: error: --reference: {t}/missing.csv not found"),
    ("fresh_missing_stored", "cryptic", ["report", "fresh", "--stored", "{t}/missing.csv", "--fresh",
                                         "{t}/fresh/head_on/seed0/kitchen_living/everywhere/h1.05.csv",
                                         "--out-prefix", "{t}/f"],
     "egosearch report: error: --stored: {t}/missing.csv not found"),
    ("bench_env_seconds_zero", "silent", ["bench", "env", "--seconds", "0"],
     "egosearch bench: error: --seconds is read by `bench gpu` only, not by `bench env`"),
    ("estimate_all_cores_100000", "silent", ["estimate", "all", "--cores", "100000"],
     re.compile(r"egosearch estimate: error: --cores=100000: at most 1024, the cores of one machine snakemake "
                r"schedules on \(this one has \d+\)")),
]

NEW48_CASES = [
    ("estimate_check_log_a_folder", "traceback", ["estimate", "check", "--log", "{t}/eval"],
     f"egosearch estimate: error: --log: {{t}}/eval is a folder; {SNAKEMAKE_LOG}"),
    ("estimate_check_log_missing", "cryptic", ["estimate", "check", "--log", "{t}/missing.log"],
     f"egosearch estimate: error: --log: {{t}}/missing.log not found; {SNAKEMAKE_LOG}"),
    ("estimate_check_record_of_another_preset", "silent",
     ["estimate", "check", "--log", "{t}/cpu.log", "--record", "{t}/smoke_record.json"],
     "egosearch estimate: error: --record: {t}/smoke_record.json holds the smoke preset's job times, but the jobs of "
     "{t}/cpu.log ran at the cpu preset: give a record of the cpu preset"),
    ("estimate_check_record_jobs_not_a_list", "traceback",
     ["estimate", "check", "--log", "{t}/cpu.log", "--record", "{t}/nojobs.json"],
     "egosearch estimate: error: --record: {t}/nojobs.json holds no list of jobs with their rule and job ('jobs'); "
     + RECORD),
    ("estimate_all_bench_result_not_an_object", "traceback",
     ["estimate", "all", "--bench", "{t}/badbench.json", "--rate", "5"],
     "egosearch estimate: error: --bench: {t}/badbench.json holds no benchmark result ('result' and 'machine' must "
     f"be objects); {BENCH}"),
    ("estimate_all_rate_infinite", "silent", ["estimate", "all", "--rate", "inf"],
     "egosearch estimate: error: --rate=inf: env steps per CPU-second must be a positive, finite number"),
    ("estimate_all_preset_without_a_run", "silent", ["estimate", "all", "--preset", "paper", "--rate", "50"],
     "egosearch estimate: error: results/paper/provenance.json records no job's time: the paper preset has no "
     "stored run to scale (--preset cpu has one)"),
    ("estimate_check_rate_zero", "silent", ["estimate", "check", "--log", "{t}/cpu.log", "--rate", "0"],
     "egosearch estimate: error: --rate is read by `estimate all` only, not by `estimate check`"),
    ("bench_learner_baseline_seconds_zero", "silent", ["bench", "learner", "--baseline-seconds", "0"],
     "egosearch bench: error: --baseline-seconds is read by `bench gpu` only, not by `bench learner`"),
    ("evaluate_frontier_in_a_head_off_env", "silent",
     ["evaluate", "--scenarios", S3, "--policy", "frontier", "--env-id", "EgoSearchNoHead-v0", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: --env-id=EgoSearchNoHead-v0 fixes the head, and --policy frontier is the searcher "
     "with the head moving: its rows would be read under that name; leave --env-id out, or use --policy "
     "frontier_head_off"),
    ("evaluate_frontier_head_off_in_a_head_on_memory_env", "silent",
     ["evaluate", "--scenarios", S3, "--policy", "frontier_head_off", "--env-id", "EgoSearchMemory-v0", "--out",
      "{t}/o.csv"],
     "egosearch evaluate: error: --env-id=EgoSearchMemory-v0 moves the head, and --policy frontier_head_off is the "
     "searcher with the head fixed: its rows would be read under that name; leave --env-id out, or use --policy "
     "frontier"),
    ("evaluate_oracle_in_a_decision_env", "silent",
     ["evaluate", "--scenarios", S3, "--policy", "oracle", "--env-id", "EgoSearchModular-v0", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: --env-id=EgoSearchModular-v0 takes a modular searcher's decisions, and --policy "
     "oracle acts at every body step: give a body env (EgoSearch-v0 or EgoSearchNoHead-v0), or leave --env-id out"),
    ("evaluate_modular_floor_in_a_head_off_map_env", "silent",
     ["evaluate", "--scenarios", S3, "--policy", "modular_random", "--env-id", "EgoSearchNoHeadMap-v0", "--out",
      "{t}/o.csv"],
     "egosearch evaluate: error: --env-id=EgoSearchNoHeadMap-v0 fixes the head, and --policy modular_random is the "
     "searcher with the head moving: its rows would be read under that name; leave --env-id out, or use --policy "
     "modular_random_head_off"),
    ("evaluate_a_modular_actor_in_a_head_off_env", "clear",
     ["evaluate", "--scenarios", "{t}/missing.csv", "--weights", "results/cpu/train/head_on_modular/seed0/actor.pt",
      "--env-id", "EgoSearchNoHead-v0", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: results/cpu/train/head_on_modular/seed0/actor.pt: this actor was trained in "
     "EgoSearchModular-v0 (4 action values, 466 observation values besides depth), not in EgoSearchNoHead-v0 (3 and "
     "34): run it in EgoSearchModular-v0"),
    ("demos_of_a_modular_variant", "cryptic",
     ["demos", "--variant", "head_on_modular", "--episodes", "1", "--out", "{t}/d.replay.npz"],
     "egosearch demos: error: --variant=head_on_modular at the cpu preset is a modular searcher (its env step is a "
     "decision, not a body step): demonstrations are the frontier searcher's body steps, which it cannot learn "
     "from; give a variant that acts at every body step (e.g. head_on_from_scratch)"),
    ("scenarios_layout_and_homes", "silent",
     ["scenarios", "--layout", "studio", "--homes", "0:2", "--n", "1", "--out", "{t}/s.csv"],
     "egosearch scenarios: error: --layout=studio and --homes=0:2 both name the homes: give one"),
    ("variant_config_sets_the_seed", "silent", ["variant", "check", "{t}/seed_in.yaml"],
     "egosearch variant: error: {t}/seed_in.yaml: config: seed is set per run (`egosearch train --seed`, the "
     "preset's seeds in the workflow config), not by a variant or --set: leave it out"),
    ("variant_objects_empty", "silent", ["variant", "check", "{t}/objects_empty.yaml"],
     "egosearch variant: error: {t}/objects_empty.yaml: train_env/objects: [] should be non-empty"),
    ("variant_check_a_folder", "cryptic", ["variant", "check", "{t}/eval"],
     f"egosearch variant: error: {{t}}/eval is a folder; {NOT_A_VARIANT}"),
    ("variant_new_from_a_missing_file", "cryptic", ["variant", "new", "tmp_bad_input_x", "--from", "{t}/missing.yaml"],
     f"egosearch variant: error: --from: {{t}}/missing.yaml: no such file; {NOT_A_VARIANT}"),
    ("report_readme_missing_page", "cryptic", ["report", "readme", "--readme", "{t}/missing.md", "--check"],
     "egosearch report: error: --readme: {t}/missing.md not found; a page of marked blocks (README.md, docs/*.md)"),
    ("report_regenerate_unknown_variant", "cryptic", ["report", "regenerate", "--variant", "nope"],
     f"egosearch report: error: --variant: variant='nope' is unknown; allowed: {ALLOWED} (files in ablations)"),
    ("pathlength_missing_scenarios", "cryptic",
     ["report", "pathlength", ev("head_on"), "--scenarios", "{t}/missing.csv", "--out-prefix", "{t}/p"],
     "egosearch report: error: --scenarios: {t}/missing.csv not found"),
    ("behaviour_missing_traces", "cryptic",
     ["report", "behaviour", "{t}/missing.npz", TRACES[1], "--out-prefix", "{t}/b"],
     "egosearch report: error: the input files: {t}/missing.npz not found"),
    ("fresh_a_copy_as_the_fresh_set", "silent",
     ["report", "fresh", "--stored", ev("head_on"), "--fresh",
      "{t}/copy/cand/seed0/kitchen_living/everywhere/h1.05.csv", "--out-prefix", "{t}/f"],
     "egosearch report: error: --fresh: {t}/copy/cand/seed0/kitchen_living/everywhere/h1.05.csv has the same content "
     f"as the --stored {ev('head_on')} (a copy?): the check reads evaluations on two different scenario sets; pass "
     "--force when they did give the same episodes"),
    ("a_report_typed_as_a_command", "cryptic", ["behaviour"],
     "egosearch: error: 'behaviour' is not a command; it is `egosearch report behaviour`, or the workflow's target "
     "`snakemake --cores 2 behaviour`"),
    ("a_command_typed_as_a_report", "cryptic", ["report", "estimate"],
     "egosearch: error: 'estimate' is not a report; it is `egosearch estimate`"),
    ("a_report_misspelt", "clear", ["report", "tabel1"],
     "egosearch: error: 'tabel1' is not a report; did you mean `egosearch report table1`?"),
]

# The workflow's config (the Snakefile's first check): (id, before, --config changes, target, the one line).
ISSUE48_CONFIGS = [
    ("screen_reference_variant_a_searcher", "cryptic", {"variant": "head_off", "reference_variant": "frontier"},
     "screen", "config reference_variant: 'frontier' is a reference searcher, not a variant (a file in ablations/, "
               "e.g. head_on)"),
    ("screen_reference_variant_unknown", "cryptic", {"variant": "head_off", "reference_variant": "nosuch"}, "screen",
     "config reference_variant: variant='nosuch' is unknown; allowed: {allowed} (files in ablations)"),
]
NEW48_CONFIGS = [
    ("compare_variant_a_searcher", "cryptic", {"variant": "oracle"}, "compare",
     "config variant: 'oracle' is a reference searcher, not a variant (a file in ablations/, e.g. head_on)"),
    ("claims_pair_with_the_random_searcher", "cryptic", {"claims_pairs": [["head_on", "random"]]}, "behaviour",
     "config claims_pairs: 'random' is a reference searcher, not a variant (a file in ablations/, e.g. head_on)"),
]
COUNTS_BEFORE_48 = {"issue": {"clear": 0, "cryptic": 9, "traceback": 3, "silent": 7, "damage": 0},
                    "new": {"clear": 2, "cryptic": 12, "traceback": 3, "silent": 13, "damage": 0}}
"""What each table's inputs did before the fix (the issue's 19 rows; the 30 new ones). After it, every one
is one clear line before any work (the tests below)."""


def test_issue_48s_counts_before_and_after():
    for table, cases in (("issue", ISSUE48_CASES + ISSUE48_CONFIGS), ("new", NEW48_CASES + NEW48_CONFIGS)):
        before = dict.fromkeys(BEFORE_KINDS_48, 0)
        for case in cases:
            before[case[1]] += 1
        assert before == COUNTS_BEFORE_48[table], table
    assert len(ISSUE48_CASES + ISSUE48_CONFIGS) == 19 and len(NEW48_CASES + NEW48_CONFIGS) == 30
    names = [c[0] for c in ISSUE_CASES + NEW_CASES + ISSUE48_CASES + NEW48_CASES + ISSUE48_CONFIGS + NEW48_CONFIGS]
    assert len(set(names)) == len(names)


@pytest.mark.parametrize("case", ISSUE48_CONFIGS + NEW48_CONFIGS, ids=[c[0] for c in ISSUE48_CONFIGS + NEW48_CONFIGS])
def test_a_config_naming_no_variant_names_its_key(case, suite, monkeypatch, capsys):
    _, _, changes, target, message = case
    monkeypatch.chdir(suite)
    with pytest.raises(SystemExit) as stop:
        checked_variants(config(**changes), argv=[target], directory=suite / "ablations")
    allowed = ", ".join(variant_names(suite / "ablations"))
    assert stop.value.code == 1 and capsys.readouterr().err == f"egosearch: error: {message.format(allowed=allowed)}\n"


# Every case of the bad-input tables, the README's: the ones above and the older tables (all one
# clear line before this issue: their tests passed).
OLDER_CASES = 17 + 11 + 18 + 13 + 3  # BAD_VARIANT_FILES, BAD_CONFIGS, the CLI, output paths, nonsense scenarios
COUNTS_BEFORE = {"clear": OLDER_CASES + 3, "cryptic": 9 + 12, "traceback": 6 + 2, "silent": 18 + 16}
COUNTS_AFTER = {"clear": OLDER_CASES + len(ISSUE_CASES) + len(NEW_CASES), "cryptic": 0, "traceback": 0, "silent": 0}


def test_the_tables_counts_before_and_after():
    before = {kind: OLDER_CASES * (kind == "clear") for kind in BEFORE_KINDS}
    for _, kind, _, _ in ISSUE_CASES + NEW_CASES:
        before[kind] += 1
    assert before == COUNTS_BEFORE
    assert len(NEW_CASES) >= 30 and len({c[0] for c in ISSUE_CASES + NEW_CASES}) == len(ISSUE_CASES + NEW_CASES)
    assert sum(COUNTS_AFTER.values()) == sum(COUNTS_BEFORE.values())


@pytest.fixture(scope="module")
def bad(tmp_path_factory):
    """The files the cases read: small copies of stored results, and spoiled ones."""
    import csv
    import json

    import numpy as np

    from egosearch.rl.config import load_config, load_variant_config
    from egosearch.rl.run_files import env_kwargs_key
    from egosearch.variants import resolve_variant

    t = tmp_path_factory.mktemp("bad")
    results = REPO / "results" / "cpu"

    def copy(src, dest):
        (t / dest).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, t / dest)
        return t / dest

    def write(dest, data: bytes):
        (t / dest).parent.mkdir(parents=True, exist_ok=True)
        (t / dest).write_bytes(data)

    rows = list(csv.DictReader(open(results / "scenarios/kitchen_living/everywhere/h1.05.csv")))

    def scenarios(dest, spoil=None):
        chosen = [dict(r) for r in rows[:3]] if spoil is None else spoil([dict(r) for r in rows[:3]])
        with open(t / dest, "w", newline="") as f:
            writer = csv.DictWriter(f, list(rows[0]))
            writer.writeheader()
            writer.writerows(chosen)

    scenarios("s3.csv")
    scenarios("s3copy.csv")
    scenarios("zhigh.csv", lambda r: [r[0], {**r[1], "target_z": "25"}, r[2]])
    scenarios("ell.csv", lambda r: [r[0], r[1], {**rows[8], "shortest_path": "0.3"}])  # ℓ 2.6298 in the stored set
    write("bin.csv", bytes(range(256)) * 4)
    write("empty.yaml", b"")
    write("bin.yaml", b"\xff\xfe\x00name: x\x9c\x80")
    write("x.pt", b"")
    for variant in ("head_on", "head_off", "random", "oracle"):
        for home in ("kitchen_living", "generated_heldout"):
            src = results / "eval" / variant / "seed0" / home / "everywhere" / "h1.05.csv"
            if src.exists():
                copy(src, f"eval/{variant}/seed0/{home}/everywhere/h1.05.csv")
    copy(results / "eval/head_on/seed0/kitchen_living/no_low_cabinets/h1.05.csv",
         "eval/head_on/seed0/kitchen_living/no_low_cabinets/h1.05.csv")
    copy(results / "eval/head_on/seed0/generated_heldout/everywhere/h1.05.csv",
         "g_in/head_on/seed0/generated_heldout/everywhere/h1.05.csv")
    copy(results / "eval/head_on/seed0/kitchen_living/everywhere/h1.05.csv",
         "pl_in/head_on/seed0/kitchen_living/everywhere/h1.05.csv")
    copy(results / "fresh/eval/head_on/seed0/kitchen_living/everywhere/h1.05.csv",
         "fresh/head_on/seed0/kitchen_living/everywhere/h1.05.csv")
    copy(results / "scenarios/kitchen_living/everywhere/h1.05.csv", "scen/kitchen_living/everywhere/h1.05.csv")
    copy(results / "train/head_on/seed0/curve.csv", "train/head_on/seed0/curve.csv")
    write("binscen/kitchen_living/everywhere/h1.05.csv", bytes(range(256)) * 4)
    write("emptyeval/cand/seed0/kitchen_living/everywhere/h1.05.csv", b"")
    write("emptyfresh/head_on/seed0/kitchen_living/everywhere/h1.05.csv", b"")
    for dest in (*(p.format(t=t) for p in TRACES), "mansion/head_on/seed0/mansion/everywhere/h1.65.npz"):
        (t / dest).parent.mkdir(parents=True, exist_ok=True)
        np.savez(t / dest, step=np.zeros(1))
    write("badtraces/head_on/seed0/kitchen_living/everywhere/h1.65.npz", b"scenario_id,step\n0,0\n")
    write("zerotraces/head_on/seed0/kitchen_living/everywhere/h1.65.npz", b"")
    # a finished run of head_on at the cpu preset, seed 0 (the one `train` may not be pointed at with another run)
    resolved = resolve_variant("head_on", "cpu", {"seed": 0})
    done = {**json.loads((results / "train/head_on/seed0/done.json").read_text()), "variant": "head_on",
            "env_id": resolved.env_id, "env_kwargs": env_kwargs_key(resolved.train_env),
            "config": resolved.config.to_dict()}
    write("run/done.json", json.dumps(done).encode())
    # issue 48: JSON records that are not what they claim, Snakemake logs of a cpu and a smoke run, a copy
    write("notjson.json", b"{bad")
    write("list.json", b"[1, 2]")
    write("nojobs.json", b'{"jobs": 5}')
    write("badbench.json", b'{"result": [1]}')
    write("smoke_record.json", json.dumps({"preset": "smoke", "jobs": [{"rule": "train", "job": "my_lr/seed0",
                                                                           "wall_s": 60.0}]}).encode())
    for preset, variant in (("cpu", "head_on"), ("smoke", "my_lr")):
        write(f"{preset}.log", "\n".join([
            "Provided cores: 2", "[Fri Nov 27 08:00:00 2026]", "localrule train:", "    jobid: 3",
            f"    benchmark: results/{preset}/benchmarks/train/{variant}/seed0.tsv",
            f"    wildcards: preset={preset}, variant={variant}, seed=0", "[Fri Nov 27 08:01:00 2026]",
            "Finished jobid: 3 (Rule: train)", ""]).encode())
    copy(results / "eval/head_on/seed0/kitchen_living/everywhere/h1.05.csv",
         "copy/cand/seed0/kitchen_living/everywhere/h1.05.csv")
    write("seed_in.yaml", (HEAD.replace("NAME", "seed_in") + "config: {seed: 5}\n").encode())
    # issue 73: variant files past the bounds of a run's length or at odds with their env id, a ';' scenario CSV
    for stem, _, text, _ in ISSUE73_VARIANT_FILES:
        write(f"{stem}.yaml", text.replace("NAME", stem).encode())
    write("semicolon.csv", (REPO / "results/cpu/scenarios/kitchen_living/everywhere/h1.05.csv").read_text()
          .replace(",", ";").encode())
    write("objects_empty.yaml", HEAD.replace("NAME", "objects_empty").replace("everywhere}", "everywhere, objects: []}")
          .encode())
    # the same scenario ids with other ℓ: another scenario set of the same names
    ref = copy(results / "eval/head_on/seed0/kitchen_living/everywhere/h1.05.csv",
               "cmp/ref/seed0/kitchen_living/everywhere/h1.05.csv")
    episodes = list(csv.DictReader(open(ref)))
    for r in episodes:
        r["shortest_path"] = f"{float(r['shortest_path']) + 1.0:.4f}"
    (t / "cmp/cand/seed0/kitchen_living/everywhere").mkdir(parents=True)
    with open(t / "cmp/cand/seed0/kitchen_living/everywhere/h1.05.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, list(episodes[0]))
        writer.writeheader()
        writer.writerows(episodes)
    # a results folder as the DAG lays it out, whose candidate trained at the smoke preset
    for variant, config in (("head_on", load_config("cpu").to_dict()),
                            ("cand", load_variant_config("smoke").to_dict())):
        copy(ref, f"prof/results/cpu/eval/{variant}/seed0/kitchen_living/everywhere/h1.05.csv")
        write(f"prof/results/cpu/train/{variant}/seed0/config.json",
              json.dumps({"variant": variant, "config": config}).encode())
    # issue 57: a stopped run of head_on at the cpu preset (its checkpoint's header) whose demonstrations are not
    # its own, or not whole
    from egosearch.rl.demos import wanted_summary
    from egosearch.rl.run_files import CHECKPOINT_FORMAT

    wanted = wanted_summary(resolved.env_id, resolved.config, resolved.train_env, "head_on")
    other = resolve_variant("head_off", "cpu", {"seed": 0})
    # another preset's: the paper preset's SAC+CURL (at smoke, head_on has its cpu learner since issue 73)
    paper = resolve_variant("head_on", "paper", {"seed": 0})
    runs = {"dr_variant": (wanted | wanted_summary(other.env_id, other.config, other.train_env, "head_off"), 50, 2),
            "dr_preset": ({k: v for k, v in (wanted | wanted_summary(paper.env_id, paper.config, paper.train_env,
                                                                    episodes=1500)).items() if k != "variant"}, 100, 2),
            "dr_npz": (wanted, 100, 3), "dr_cut": (wanted, 50, 2), "dr_nosummary": (wanted, 50, 2)}
    for run, (summary, side, transitions) in runs.items():
        header = {"format": CHECKPOINT_FORMAT, "variant": "head_on", "env_id": resolved.env_id,
                  "env_kwargs": env_kwargs_key(resolved.train_env), "config": resolved.config.to_dict()}
        (t / run / "ckpt").mkdir(parents=True)
        torch.save(header, t / run / "ckpt" / "train_state.ckpt")
        fake_demos(t / run / "ckpt" / "demos.replay.npz", side, transitions, {**summary, "transitions": 2})
    # item 8: per-step traces for the failure-kind table, in and out of the workflow's layout
    trace = REPO / "results/cpu/traces/head_on/seed0/kitchen_living/everywhere/h1.05.npz"
    cell = "head_on/seed0/kitchen_living/everywhere"
    for dest in (f"f57/tr/{cell}/h1.05.npz", "f57/flat/h1.05.npz", "f57/odd/head_on/seed0/kitchen_living/under_sofa/"
                 "h1.05.npz", f"f57/odd/{cell}/trace.npz", f"f57/odd/{cell}/h7.npz",
                 f"f57/results/cpu/traces/{cell}/h1.05.npz", f"f57/results/smoke/traces/{cell}/h1.65.npz"):
        copy(trace, dest)
    copy(trace.with_suffix(".csv"), f"f57/tr/{cell}/h1.05.csv")
    with np.load(trace) as data:
        arrays = {k: (data[k][:0] if data[k].ndim else data[k]) for k in data.files}
    (t / f"f57/noep/{cell}").mkdir(parents=True)
    np.savez(t / f"f57/noep/{cell}/h1.05.npz", **arrays)
    cut = (t / "dr_cut/ckpt/demos.replay.npz").read_bytes()
    (t / "dr_cut/ckpt/demos.replay.npz").write_bytes(cut[: len(cut) // 2])
    (t / "dr_nosummary/ckpt/demos.json").unlink()
    return t


def fake_demos(path: Path, side: int, transitions: int, summary: dict) -> None:
    """A demonstrations file of ``transitions`` blank steps with ``side`` px frames, and the summary ``summary``."""
    import json

    import numpy as np

    from egosearch.rl.demos import DEMO_FORMAT, summary_path
    from egosearch.rl.replay import ReplayBuffer

    k, state_dim = summary["frame_history"], 4
    buffer = ReplayBuffer(transitions, side, k, 8, 4, 5, state_dim=state_dim)
    obs = {"depth": np.zeros((k, side, side), np.uint8), "mask": np.zeros(8), "proprio": np.zeros(4),
           "state": np.zeros(state_dim)}
    for step in range(transitions):
        buffer.add(obs, np.zeros(5), 0.0, obs, False, step == transitions - 1)
    buffer.save(path)
    summary_path(path).write_text(json.dumps({"format": DEMO_FORMAT, **summary, "state_dim": state_dim}))


@pytest.fixture
def nothing_runs(monkeypatch):
    """Any episode, training step, scenario draw, benchmark or picture fails the test: each bad input
    must be refused before it."""
    import egosearch.cli.bench
    import egosearch.cli.demos
    import egosearch.cli.estimate
    import egosearch.cli.evaluate
    import egosearch.cli.fullbody
    import egosearch.cli.pictures
    import egosearch.cli.scenarios
    import egosearch.cli.video
    import egosearch.cost.estimate
    import egosearch.cost.schedule_check
    import egosearch.rl.train

    def work(*args, **kwargs):
        raise AssertionError("work started before the bad input was refused")

    for module, name in ((egosearch.cli.evaluate, "evaluate"), (egosearch.cli.fullbody, "evaluate_fullbody"),
                         (egosearch.cli.video, "write_search_video"), (egosearch.cli.scenarios, "generate_scenarios"),
                         (egosearch.cli.bench, "gpu_check"), (egosearch.cli.bench, "bench_learner"),
                         (egosearch.cli.bench.bench, "bench_env"), (egosearch.cli.pictures, "make_pictures"),
                         (egosearch.rl.train, "_train"), (egosearch.cost.estimate, "dag_jobs"),
                         (egosearch.cost.schedule_check, "dag_jobs"), (egosearch.cli.estimate, "calibrate"),
                         (egosearch.cli.demos, "collect_demonstrations")):
        monkeypatch.setattr(module, name, work)


def _filled(value, t: Path):
    if isinstance(value, re.Pattern):
        return re.compile(value.pattern.replace("{t}", re.escape(str(t))))
    built = "a CPU-only build" if not torch.version.cuda else f"built with CUDA {torch.version.cuda}"
    return value.replace("{t}", str(t)).replace("{torch}", f"{torch.__version__} ({built})")


CLI_CASES = ISSUE_CASES + NEW_CASES + ISSUE48_CASES + NEW48_CASES


@pytest.mark.parametrize("case", CLI_CASES, ids=[c[0] for c in CLI_CASES])
def test_each_bad_input_is_one_clear_line_before_any_work(case, bad, capsys, monkeypatch, nothing_runs):
    name, _, argv, expected = case
    if "cuda" in name and torch.cuda.is_available():
        pytest.skip("this machine has CUDA: bench gpu runs")
    monkeypatch.chdir(REPO)  # the stored results are the checkout's
    before = sorted(p.relative_to(bad) for p in bad.rglob("*"))
    variants_before = variant_names(REPO / "ablations")
    line = cli_error(capsys, *[_filled(arg, bad) for arg in argv])
    expected = _filled(expected, bad)
    if isinstance(expected, re.Pattern):
        assert expected.fullmatch(line), line
    else:
        assert line == expected
    # nothing written, not even a temporary file or an empty folder, nor a variant file left behind
    assert sorted(p.relative_to(bad) for p in bad.rglob("*")) == before
    assert not (REPO / "ablations" / "tmp_bad_input_x.yaml").exists()
    assert variant_names(REPO / "ablations") == variants_before


def test_the_overwrite_guard_without_git_reads_the_provenance(tmp_path, monkeypatch):
    """An unpacked archive has no git to ask: the sha256 list of results/<preset>/provenance.json
    says what is stored, and paper_figs/ beside such a record is stored too."""
    import json

    from egosearch.core.outputs import OutputPathError, check_overwrites, stored_results

    stored = tmp_path / "results/cpu/eval/x/seed0/h/everywhere/h1.05.csv"
    new = tmp_path / "results/cpu/eval/y/seed0/h/everywhere/h1.05.csv"
    figure = tmp_path / "paper_figs/cpu/table1.md"
    for path in (stored, new, figure):
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("x")
    (tmp_path / "results/cpu/provenance.json").write_text(json.dumps(
        {"files": {"eval/x/seed0/h/everywhere/h1.05.csv": {"sha256": "0", "bytes": 1}}}))
    monkeypatch.setenv("GIT_CEILING_DIRECTORIES", str(tmp_path.parent))
    found = stored_results([stored, new, figure, tmp_path / "results/cpu/not_yet.csv", tmp_path / "results/cpu"])
    assert set(found) == {stored, figure, tmp_path / "results/cpu"}
    assert found[stored][1] == "listed in the results' provenance.json"
    with pytest.raises(OutputPathError, match="is a stored result .*pass --force"):
        check_overwrites(files={"--out": stored})
    check_overwrites(files={"--out": stored}, force=True)          # --force: the DAG's jobs
    check_overwrites(files={"--out": new})                           # not in the record: a new result
    check_overwrites(files={"--out": tmp_path / "results/cpu/not_yet.csv"})  # not there yet: never refused
    with pytest.raises(OutputPathError, match="is also an input"):  # whatever --force says
        check_overwrites(files={"--out": new}, inputs={"--scenarios": new}, force=True)


def test_a_stored_result_is_what_git_tracks():
    from egosearch.core.outputs import stored_results

    tracked = REPO / "results/cpu/provenance.json"
    untracked = REPO / "results/cpu/logs"  # a folder holding tracked logs
    found = stored_results([tracked, untracked, REPO / "README.md", REPO / "results/cpu/nothing_here.csv"])
    assert set(found) == {tracked, untracked}


def test_the_dags_own_jobs_pass_force():
    """Every command the DAG runs that writes a file passes --force, and nothing else needs it."""
    writers = re.compile(r'"egosearch (scenarios|evaluate|train|fullbody|video|pictures|report (?!regenerate|readme|'
                         r'verify)\w+)')
    lines = [line for path in sorted((REPO / "egosearch/workflow/rules").glob("*.smk"))
             for line in path.read_text().splitlines() if writers.search(line)]
    assert len(lines) >= 20 and all("--force" in line for line in lines), [x for x in lines if "--force" not in x]


def test_a_compare_that_fails_a_check_leaves_no_file(bad, capsys):
    """The ℓ check runs after the cell table is computed: its CSV waits in a temporary file."""
    out = bad / "cmp_out" / "c.csv"
    assert cli_error(capsys, "report", "compare", "--reference",
                     str(bad / "cmp/ref/seed0/kitchen_living/everywhere/h1.05.csv"), "--candidate",
                     str(bad / "cmp/cand/seed0/kitchen_living/everywhere/h1.05.csv"), "--out",
                     str(out)).endswith("not the same scenarios")
    assert not out.parent.exists() or not list(out.parent.iterdir())


def test_a_compare_that_passes_writes_its_files_under_their_names(bad, capsys):
    out = bad / "cmp_ok" / "c.csv"
    assert main(["report", "compare", "--reference", str(bad / "cmp/ref/seed0/kitchen_living/everywhere/h1.05.csv"),
                 "--candidate", str(bad / "eval/head_off/seed0/kitchen_living/everywhere/h1.05.csv"), "--out",
                 str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"wrote {out}\n" in printed and f"wrote {out.parent / 'c_by_length.csv'}\n" in printed
    assert f"wrote {out.parent / 'c_stuck.csv'}\n" in printed
    assert ".tmp" not in printed
    assert sorted(p.name for p in out.parent.iterdir()) == ["c.csv", "c_by_length.csv", "c_stuck.csv"]


def test_a_smoke_actor_gets_a_note_naming_its_preset(capsys):
    """Evaluated beside the cpu results, a smoke actor's rows would pass for a poor variant's."""
    import json
    from types import SimpleNamespace

    from egosearch.cli.acting import note_preset
    from egosearch.cli.checks import learner_preset_of
    from egosearch.rl.config import load_variant_config

    note_preset("smoke.pt", SimpleNamespace(config=load_variant_config("smoke").to_dict(), variant="head_on"))
    assert capsys.readouterr().err == ("note: smoke.pt was trained at the smoke learner preset (its config is the "
                                       "smoke preset's), not at cpu: do not read its results beside the cpu "
                                       "preset's\n")
    # every stored run reads as the preset of the folder it is stored in
    for config in sorted(REPO.glob("results/*/train/*/seed*/config.json")):
        record = json.loads(config.read_text())
        assert learner_preset_of(record["config"], record.get("variant"))[0] == config.parts[-5], config


def test_help_names_every_layout_the_commands_take(capsys):
    from egosearch.scene.layouts import EASY_LAYOUTS, LAYOUT_NAMES

    for argv in (["scenarios", "--help"], ["pictures", "--help"], ["bench", "--help"]):
        with pytest.raises(SystemExit):
            main(argv)
        out = " ".join(capsys.readouterr().out.split())
        assert all(name in out for name in (*LAYOUT_NAMES, *EASY_LAYOUTS, "home<seed>")), argv
    for argv in (["train", "--help"], ["bench", "--help"]):
        with pytest.raises(SystemExit):
            main(argv)
        out = " ".join(capsys.readouterr().out.split())
        assert "SAC-DrQ at cpu" in out, argv


# --------------------------------------------------------------------------- issue 57: a newcomer's third round
# The same form as issue 48's tables: (id, what it did before the fix, the input, the one line now). The
# rows of the issue's items 4, 6 and 7 that were cryptic or silent.
ISSUE57_CASES = [
    ("table1_bounds_a_searchers_name", "cryptic",
     ["report", "table1", ev("head_on"), "--bounds", "frontier", "--out-prefix", "{t}/t"],
     "egosearch report: error: --bounds: frontier not found; --bounds takes evaluation CSV paths, not a searcher's "
     "name: frontier's are results/<preset>/eval/frontier/seed<N>/<home>/<placement>/h<height>.csv"),
    ("table1_bounds_a_missing_csv", "cryptic",
     ["report", "table1", ev("head_on"), "--bounds", "{t}/missing.csv", "--out-prefix", "{t}/t"],
     "egosearch report: error: --bounds: {t}/missing.csv not found; --bounds takes the evaluation CSV paths of the "
     f"searchers ({BOUNDS}): results/<preset>/eval/<searcher>/seed<N>/<home>/<placement>/h<height>.csv"),
]
TPG = "allowed: 'auto' or an integer from 1 to 64"
ISSUE57_CONFIGS = [
    ("trainings_per_gpu_a_word", "cryptic", {"trainings_per_gpu": "many"}, "all",
     f"config trainings_per_gpu: 'many' is not allowed; {TPG}"),
    ("trainings_per_gpu_a_fraction", "cryptic", {"trainings_per_gpu": 2.5}, "all",
     f"config trainings_per_gpu: 2.5 is not allowed; {TPG}"),
    ("trainings_per_gpu_capitalised", "cryptic", {"trainings_per_gpu": "Auto"}, "all",
     f"config trainings_per_gpu: 'Auto' is not allowed (did you mean 'auto'?); {TPG}"),
    ("trainings_per_gpu_zero", "clear", {"trainings_per_gpu": 0}, "all",
     f"config trainings_per_gpu: 0 is not allowed; {TPG}"),
]
ISSUE57_VARIANT_FILES = [
    ("top_level_preset", "cryptic", HEAD + "preset: turbo\n",
     "ablations/top_level_preset.yaml: (top level): 'preset' is not a key here; allowed: name, description, "
     "env_id, train_env, config"),
    ("train_env_key_typo", "cryptic", HEAD.replace("everywhere}", "everywhere, objets: [mug]}"),
     "ablations/train_env_key_typo.yaml: train_env: 'objets' (did you mean 'objects'?) is not a key here; allowed: "
     "layout, placement, objects, distance_reward, coverage_bonus, home_seeds"),
]
# (id, before, the snakemake arguments after -n, the one line)
ISSUE57_SNAKEMAKE = [
    ("paper_gpu_slots_zero", "silent", ["all", "--config", "preset=paper", "--resources", "gpu_slots=0"],
     "egosearch: error: --resources gpu_slots=0: every paper-preset training asks for one gpu_slots (its share of "
     "the GPU), so none could start; give gpu_slots=1 or more (the trainings side by side on one GPU), or leave it "
     "out (config trainings_per_gpu sets it: 6 here)"),
]
# (id, before, the gymnasium id, its keyword options, the one line of the ValueError gymnasium.make raises)
ISSUE57_ENV_OPTIONS = [
    ("nohead_id_with_the_head", "silent", "egosearch:EgoSearchNoHead-v0", {"head": True},
     "head=True contradicts EgoSearchNoHead-v0, which fixes head=False (the camera's two joints off); allowed: "
     "head=False, or leave head out (EgoSearch-v0 is the id with head=True)"),
    ("modular_id_with_target_memory", "silent", "egosearch:EgoSearchModular-v0", {"target_memory": True},
     "target_memory=True: EgoSearchModular-v0 does not read target_memory (its observation is the decision's: the "
     "mask's features and the searcher's map); allowed: leave target_memory out (a body env reads it, e.g. "
     "EgoSearchMemory-v0)"),
    ("floor_map_without_target_memory", "silent", "egosearch:EgoSearch-v0", {"floor_map": True},
     "floor_map=True in EgoSearch-v0 needs target_memory=True (the floor map comes with the target memory: "
     "EgoSearchMap-v0 and EgoSearchNoHeadMap-v0); allowed: floor_map with target_memory=True, or floor_map=False"),
    ("height_a_string", "cryptic", "egosearch:EgoSearch-v0", {"height": "1.05"},
     "height='1.05' is a str, not a number; allowed: a number of metres in [0.3, 2.0]"),
    ("max_steps_zero", "silent", "egosearch:EgoSearch-v0", {"max_steps": 0},
     "max_steps=0: every episode would end before its first step; allowed: an integer >= 1 (T_max: the steps "
     "before an episode is truncated)"),
    # beyond the issue's rows: the same kinds on the other ids
    ("head_id_without_the_head", "silent", "egosearch:EgoSearch-v0", {"head": False},
     "head=False contradicts EgoSearch-v0, which fixes head=True (the camera's two joints on); allowed: head=True, "
     "or leave head out (EgoSearchNoHead-v0 is the id with head=False)"),
    ("memory_id_without_the_memory", "silent", "egosearch:EgoSearchMemory-v0", {"target_memory": False},
     "target_memory=False contradicts EgoSearchMemory-v0, which fixes target_memory=True (the last-seen target "
     "memory on); allowed: target_memory=True, or leave target_memory out (EgoSearch-v0 is the id with "
     "target_memory=False)"),
    ("modular_id_with_the_floor_map", "silent", "egosearch:EgoSearchNoHeadModular-v0", {"floor_map": True},
     "floor_map=True: EgoSearchNoHeadModular-v0 does not read floor_map (its observation is the decision's: the "
     "mask's features and the searcher's map); allowed: leave floor_map out (a body env reads it, e.g. "
     "EgoSearchMap-v0)"),
    ("nohead_modular_id_with_the_head", "silent", "egosearch:EgoSearchNoHeadModular-v0", {"head": True},
     "head=True contradicts EgoSearchNoHeadModular-v0, which fixes head=False (the camera's two joints off); "
     "allowed: head=False, or leave head out (EgoSearchModular-v0 is the id with head=True)"),
    ("head_a_word", "silent", "egosearch:EgoSearchNoHead-v0", {"head": "no"},
     "head='no' is a str; allowed: True or False"),
    ("max_steps_a_fraction", "silent", "egosearch:EgoSearch-v0", {"max_steps": 2.5},
     "max_steps=2.5 is a float; allowed: an integer >= 1 (T_max: the steps before an episode is truncated)"),
    ("max_steps_negative_in_a_decision_env", "silent", "egosearch:EgoSearchModular-v0", {"max_steps": -5},
     "max_steps=-5: every episode would end before its first step; allowed: an integer >= 1 (T_max: the steps "
     "before an episode is truncated)"),
]
# Item 3: a stopped run of head_on (cpu, seed 0) resumed with demonstrations that are not its own, or not whole
# (fixture `bad`): refused before any env is built, naming the file and what was expected.
RESUME = "egosearch train: error: --out-dir: {t}/%s/ckpt/train_state.ckpt cannot resume with its demonstrations: "
HEAD_ON_KWARGS = ("{'contact_signal': True, 'distance_reward': 'geodesic', 'train_heights': [0.45, 1.8], "
                  "'privileged_state': True, 'layout': 'paper_homes', 'placement': 'everywhere'}")
ISSUE57_DEMOS = [
    ("train_resume_with_another_variants_demos", "traceback", ["train", "--variant", "head_on", "--out-dir",
                                                               "{t}/dr_variant"],
     RESUME % "dr_variant" + "{t}/dr_variant/ckpt/demos.replay.npz holds other demonstrations than this run's: "
     "variant='head_off', env_id='EgoSearchNoHeadMemory-v0'; expected variant='head_on', env_id='EgoSearchMemory-v0'"),
    ("train_resume_with_another_presets_demos", "traceback", ["train", "--variant", "head_on", "--out-dir",
                                                               "{t}/dr_preset"],
     RESUME % "dr_preset" + "{t}/dr_preset/ckpt/demos.replay.npz holds other demonstrations than this run's: "
     "env_id='EgoSearch-v0', env_kwargs={'layout': 'paper_homes', 'placement': 'everywhere'}, teacher='frontier', "
     f"image_size=100; expected env_id='EgoSearchMemory-v0', env_kwargs={HEAD_ON_KWARGS}, teacher='frontier_tuned', "
     "image_size=50"),
    ("train_resume_with_the_npz_replaced", "cryptic", ["train", "--variant", "head_on", "--out-dir", "{t}/dr_npz"],
     RESUME % "dr_npz" + "{t}/dr_npz/ckpt/demos.replay.npz does not match its summary demos.json: the file holds "
     "image_size=100, transitions=3; the summary says image_size=50, transitions=2"),
    ("train_resume_with_a_truncated_npz", "traceback", ["train", "--variant", "head_on", "--out-dir", "{t}/dr_cut"],
     RESUME % "dr_cut" + "{t}/dr_cut/ckpt/demos.replay.npz: not a readable demonstrations file, truncated or corrupt "
     "(BadZipFile: File is not a zip file); expected the .npz `egosearch demos` writes, of 2 transitions as "
     "demos.json says"),
    ("train_resume_without_the_demos_summary", "cryptic", ["train", "--variant", "head_on", "--out-dir",
                                                           "{t}/dr_nosummary"],
     RESUME % "dr_nosummary" + "{t}/dr_nosummary/ckpt/demos.replay.npz: its summary {t}/dr_nosummary/ckpt/demos.json "
     "is not there (`egosearch demos` writes both)"),
]
# (id, before, the input): accepted now, as what it means
ISSUE57_ACCEPTED = [
    ("variant_file_bare_config", "cryptic", HEAD + "config:\n"),
]
COUNTS_BEFORE_57 = {"clear": 1, "cryptic": 11, "traceback": 3, "silent": 12, "damage": 0}
"""What the rows above did before the fix; after it each is one clear line before any work."""


# --------------------------------------------------------------------------- issue 57, item 8: 30 new bad inputs
# In what the other open issues add: the failure-kind table (`egosearch report failures`, rule `failures`, its
# traces and config claims_pairs), printing a config (`egosearch report table2`, `egosearch variant check`) and
# env options at evaluation (`egosearch evaluate --env-id`). The cluster profile (profiles/slurm) is not on this
# branch: none of its inputs here. (id, what it did before the fixes, argv, the one line now), as ISSUE_CASES.
F57 = "{t}/f57/tr/head_on/seed0/kitchen_living/everywhere/h1.05"
FAILURES = ["report", "failures", F57 + ".npz", "--out-prefix"]
ENV_IDS = ("EgoSearch-v0, EgoSearchNoHead-v0, EgoSearchMemory-v0, EgoSearchNoHeadMemory-v0, EgoSearchMap-v0, "
           "EgoSearchNoHeadMap-v0, EgoSearchModular-v0, EgoSearchNoHeadModular-v0")
LAID_OUT = "expected .../{variant}/seed{seed}/{layout}/{placement}/h{height}.npz"
EVALUATE = ["evaluate", "--scenarios", S3, "--out", "{t}/o.csv"]
HEAD_ON_ACTOR = "results/cpu/train/head_on/seed0/actor.pt"
ISSUE57_NEW_CASES = [
    ("failures_trace_outside_the_layout", "silent",  # its method was whatever folder held it
     ["report", "failures", "{t}/f57/flat/h1.05.npz", "--out-prefix", "{t}/f"],
     f"egosearch report: error: {{t}}/f57/flat/h1.05.npz: {LAID_OUT}"),
    ("failures_an_evaluation_csv", "clear", ["report", "failures", ev("head_on"), "--out-prefix", "{t}/f"],
     f"egosearch report: error: the input files: {ev('head_on')} is not an .npz file (numpy's zip format); a trace "
     "file is written by `egosearch evaluate --traces`"),
    ("failures_npz_without_the_trace_arrays", "traceback", ["report", "failures", TRACES[0], "--out-prefix", "{t}/f"],
     f"egosearch report: error: {TRACES[0]}: not a per-step trace (it lacks scenario_id, collisions, visible, "
     "success, geodesic); a trace file is written by `egosearch evaluate --traces`"),
    ("failures_empty_npz", "clear", ["report", "failures", "{t}/zerotraces/head_on/seed0/kitchen_living/everywhere/"
                                     "h1.65.npz", "--out-prefix", "{t}/f"],
     "egosearch report: error: the input files: {t}/zerotraces/head_on/seed0/kitchen_living/everywhere/h1.65.npz is "
     "empty; a trace file is written by `egosearch evaluate --traces`"),
    ("failures_trace_of_no_episode", "traceback",
     ["report", "failures", "{t}/f57/noep/head_on/seed0/kitchen_living/everywhere/h1.05.npz", "--out-prefix", "{t}/f"],
     "egosearch report: error: {t}/f57/noep/head_on/seed0/kitchen_living/everywhere/h1.05.npz: a trace of no episode "
     "(its scenario set was empty); a failure table reads at least one"),
    ("failures_same_trace_twice", "silent", [*FAILURES[:3], F57 + ".npz", "--out-prefix", "{t}/f"],
     f"egosearch report: error: the input files: {F57}.npz is given twice: give each trace once (its episodes would "
     "count twice)"),
    ("failures_unknown_placement_folder", "silent",
     ["report", "failures", "{t}/f57/odd/head_on/seed0/kitchen_living/under_sofa/h1.05.npz", "--out-prefix", "{t}/f"],
     "egosearch report: error: {t}/f57/odd/head_on/seed0/kitchen_living/under_sofa/h1.05.npz: its placement folder "
     "'under_sofa' is none of no_low_cabinets, everywhere; expected .../<method>/seed<N>/<home>/<placement>/"
     "h<height>.npz, as the workflow lays traces out"),
    ("failures_trace_not_named_by_its_height", "clear",
     ["report", "failures", "{t}/f57/odd/head_on/seed0/kitchen_living/everywhere/trace.npz", "--out-prefix", "{t}/f"],
     f"egosearch report: error: {{t}}/f57/odd/head_on/seed0/kitchen_living/everywhere/trace.npz: {LAID_OUT}"),
    ("failures_height_of_no_camera", "silent",
     ["report", "failures", "{t}/f57/odd/head_on/seed0/kitchen_living/everywhere/h7.npz", "--out-prefix", "{t}/f"],
     "egosearch report: error: {t}/f57/odd/head_on/seed0/kitchen_living/everywhere/h7.npz: height 7 m is outside "
     "[0.3, 2.0] m, the camera heights a trace can have"),
    ("failures_out_prefix_ending_in_csv", "silent", [*FAILURES, "{t}/f.csv"],
     "egosearch report: error: --out-prefix={t}/f.csv ends in .csv, and failures adds .csv, _stuck.csv and .md to it "
     "({t}/f.csv.csv); allowed: the prefix without .csv, {t}/f"),
    ("failures_out_prefix_beside_a_trace", "damage", [*FAILURES, F57],  # overwrote the trace's episodes CSV
     f"egosearch report: error: --out-prefix={F57} writes {F57}.csv, which is also an input (the traces' episodes "
     "CSVs): a command never writes over its own input; choose another output path"),
    ("failures_out_prefix_stored", "clear", [*FAILURES, "paper_figs/cpu/failures"],
     re.compile(r"egosearch report: error: --out-prefix=paper_figs/cpu/failures writes paper_figs/cpu/failures\.csv, "
                rf"which is a stored result {STORED}; pass --force to overwrite it, or write elsewhere")),
    ("failures_stuck_read_twice", "silent", [*FAILURES, "{t}/f", "--stuck-read", "head_on", "head_on"],
     "egosearch report: error: --stuck-read: head_on is given twice; each method's section is written once"),
    ("failures_of_two_presets", "silent",
     ["report", "failures", "{t}/f57/results/cpu/traces/head_on/seed0/kitchen_living/everywhere/h1.05.npz",
      "{t}/f57/results/smoke/traces/head_on/seed0/kitchen_living/everywhere/h1.65.npz", "--out-prefix", "{t}/f"],
     "egosearch report: error: the input files mix presets: {t}/f57/results/cpu/traces/head_on/seed0/kitchen_living/"
     "everywhere/h1.05.npz is cpu's, {t}/f57/results/smoke/traces/head_on/seed0/kitchen_living/everywhere/h1.65.npz "
     "is smoke's; a failure table reads one preset's traces"),
    ("failures_out_prefix_empty", "silent", [*FAILURES, ""],  # wrote .csv, _stuck.csv and .md where it ran
     "egosearch report: error: --out-prefix='' is empty; allowed: a path to which failures adds .csv, _stuck.csv and "
     ".md (e.g. paper_figs/cpu/failures)"),
    ("failures_stuck_read_a_searcher_not_given", "clear", [*FAILURES, "{t}/f", "--stuck-read", "frontier"],
     "egosearch report: error: --stuck-read: frontier has no trace among the input files (head_on)"),
    ("table2_unknown_preset", "clear", ["report", "table2", "--preset", "fast", "--out-prefix", "{t}/t2"],
     "egosearch report: error: unknown preset 'fast'; allowed: smoke, cpu, paper"),
    ("table2_out_prefix_ending_in_md", "silent", ["report", "table2", "--preset", "cpu", "--out-prefix", "{t}/t2.md"],
     "egosearch report: error: --out-prefix={t}/t2.md ends in .md, and table2 adds .md and .tex to it ({t}/t2.md.md); "
     "allowed: the prefix without .md, {t}/t2"),
    ("table2_out_prefix_stored", "clear",
     ["report", "table2", "--preset", "paper", "--out-prefix", "paper_figs/table2"],
     re.compile(r"egosearch report: error: --out-prefix=paper_figs/table2 writes paper_figs/table2\.md, which is a "
                rf"stored result {STORED}; pass --force to overwrite it, or write elsewhere")),
    ("table2_out_prefix_empty", "silent", ["report", "table2", "--preset", "cpu", "--out-prefix", ""],
     "egosearch report: error: --out-prefix='' is empty; allowed: a path to which table2 adds .md and .tex (e.g. "
     "paper_figs/cpu/table2)"),
    ("variant_check_a_preset_twice", "silent", ["variant", "check", "head_on", "--preset", "cpu", "cpu"],
     "egosearch variant: error: --preset: cpu is given twice; each preset is checked once"),
    ("variant_check_a_name_with_its_suffix", "clear", ["variant", "check", "head_on.yaml"],
     f"egosearch variant: error: head_on.yaml: no such file; {NOT_A_VARIANT}"),
    ("variant_check_capitalised", "clear", ["variant", "check", "Head_On"],
     f"egosearch variant: error: variant='Head_On' is unknown (did you mean 'head_on'?); allowed: {ALLOWED} (files "
     "in ablations)"),
    ("evaluate_env_id_as_gymnasium_writes_it", "clear", [*EVALUATE, "--policy", "random", "--env-id",
                                                         "egosearch:EgoSearch-v0"],
     f"egosearch evaluate: error: --env-id='egosearch:EgoSearch-v0'; allowed: {ENV_IDS}"),
    ("evaluate_env_id_of_another_version", "clear", [*EVALUATE, "--policy", "random", "--env-id", "EgoSearch-v1"],
     f"egosearch evaluate: error: --env-id='EgoSearch-v1'; allowed: {ENV_IDS}"),
    ("evaluate_env_id_in_lower_case", "clear", [*EVALUATE, "--policy", "random", "--env-id", "egosearch-v0"],
     f"egosearch evaluate: error: --env-id='egosearch-v0'; allowed: {ENV_IDS}"),
    ("evaluate_env_id_empty", "silent", [*EVALUATE, "--policy", "random", "--env-id", ""],  # ran in EgoSearch-v0
     f"egosearch evaluate: error: --env-id=''; allowed: {ENV_IDS}"),
    ("evaluate_random_in_a_decision_env", "clear", [*EVALUATE, "--policy", "random", "--env-id",
                                                    "EgoSearchModular-v0"],
     "egosearch evaluate: error: --env-id=EgoSearchModular-v0 takes a modular searcher's decisions, and --policy "
     "random acts at every body step: give a body env (EgoSearch-v0 or EgoSearchNoHead-v0), or leave --env-id out"),
    ("evaluate_an_actor_without_its_memory", "clear", [*EVALUATE, "--weights", HEAD_ON_ACTOR, "--env-id",
                                                       "EgoSearch-v0"],
     f"egosearch evaluate: error: {HEAD_ON_ACTOR}: this actor was trained in EgoSearchMemory-v0 with contact_signal "
     "(5 action values, 41 observation values besides depth), not in EgoSearch-v0 with contact_signal (5 and 36): "
     "run it in EgoSearchMemory-v0 with contact_signal"),
    ("evaluate_an_actor_with_a_floor_map", "clear", [*EVALUATE, "--weights", HEAD_ON_ACTOR, "--env-id",
                                                     "EgoSearchMap-v0"],
     f"egosearch evaluate: error: {HEAD_ON_ACTOR}: this actor was trained in EgoSearchMemory-v0 with contact_signal "
     "(5 action values, 41 observation values besides depth), not in EgoSearchMap-v0 with contact_signal (5 and 188): "
     "run it in EgoSearchMemory-v0 with contact_signal"),
    ("evaluate_the_tuned_searcher_head_fixed", "clear", [*EVALUATE, "--policy", "frontier_tuned", "--env-id",
                                                         "EgoSearchNoHeadMemory-v0"],
     "egosearch evaluate: error: --env-id=EgoSearchNoHeadMemory-v0 fixes the head, and --policy frontier_tuned is the "
     "searcher with the head moving: its rows would be read under that name; leave --env-id out, or use --policy "
     "frontier_tuned_head_off"),
    ("evaluate_env_id_for_an_actor_without_weights", "clear", [*EVALUATE, "--policy", "actor", "--env-id",
                                                               "EgoSearch-v0"],
     "egosearch evaluate: error: --policy actor needs --weights PATH/actor.pt"),
]
# The rule `failures` reads config claims_pairs (its traces, the pair whose stuck episodes it reads): as
# ISSUE48_CONFIGS, (id, before, --config changes, target, the one line)
ISSUE57_NEW_CONFIGS = [
    ("claims_pair_given_twice", "silent", {"claims_pairs": [["head_on", "head_off"], ["head_on", "head_off"]]},
     "failures", "config claims_pairs: ['head_on', 'head_off'] is given twice; each pair once"),
    ("claims_pairs_empty", "clear", {"claims_pairs": []}, "failures", "config claims_pairs: [] should be non-empty"),
]
# accepted now, as what it means: a folder as the prefix (the other reports' rule) wrote hidden files .csv,
# _stuck.csv and .md in it
ISSUE57_NEW_ACCEPTED = [("failures_out_prefix_a_folder", "silent")]
COUNTS_BEFORE_57_NEW = {"clear": 18, "cryptic": 0, "traceback": 2, "silent": 14, "damage": 1}
"""What the 35 new inputs did before the fixes; after them each is one clear line before any work, or, for the
folder prefix, what it means."""


def test_issue_57s_new_inputs_count_before_and_after():
    rows = ([c[:2] for c in ISSUE57_NEW_CASES] + [c[:2] for c in ISSUE57_NEW_CONFIGS] + ISSUE57_NEW_ACCEPTED)
    before = dict.fromkeys(BEFORE_KINDS_48, 0)
    for _, kind in rows:
        before[kind] += 1
    assert before == COUNTS_BEFORE_57_NEW and len(rows) >= 30
    names = [name for name, _ in rows + issue57_rows()] + [c[0] for c in CLI_CASES]
    assert len(set(names)) == len(names)


@pytest.mark.parametrize("case", ISSUE57_NEW_CASES, ids=[c[0] for c in ISSUE57_NEW_CASES])
def test_issue_57s_new_inputs_are_one_clear_line(case, bad, capsys, monkeypatch, nothing_runs):
    test_each_bad_input_is_one_clear_line_before_any_work(case, bad, capsys, monkeypatch, nothing_runs)


@pytest.mark.parametrize("case", ISSUE57_NEW_CONFIGS, ids=[c[0] for c in ISSUE57_NEW_CONFIGS])
def test_issue_57s_new_configs_are_one_line(case, suite, monkeypatch, capsys):
    test_a_config_naming_no_variant_names_its_key(case, suite, monkeypatch, capsys)


def test_a_folder_as_the_failure_tables_prefix_holds_its_files(bad, tmp_path, capsys):
    """A folder as --out-prefix writes failures.csv, failures_stuck.csv and failures.md in it, as every other
    report does with its own name (it wrote .csv, _stuck.csv and .md, hidden, and the overwrite guard had
    checked failures.csv)."""
    folder = tmp_path / "pages"
    folder.mkdir()
    trace = _filled(F57 + ".npz", bad)
    assert main(["report", "failures", trace, "--out-prefix", f"{folder}/", "--stuck-read", "head_on"]) == 0
    assert sorted(p.name for p in folder.iterdir()) == ["failures.csv", "failures.md", "failures_stuck.csv"]
    assert "## What `head_on` is stuck against" in (folder / "failures.md").read_text()
    assert (folder / "failures.csv").read_text().splitlines()[1].startswith("head_on,1.05,everywhere,")


def issue57_rows():
    return ([c[:2] for c in ISSUE57_CASES] + [c[:2] for c in ISSUE57_CONFIGS]
            + [c[:2] for c in ISSUE57_VARIANT_FILES] + [c[:2] for c in ISSUE57_SNAKEMAKE]
            + [c[:2] for c in ISSUE57_ACCEPTED] + [c[:2] for c in ISSUE57_ENV_OPTIONS] + [c[:2] for c in ISSUE57_DEMOS])


def test_issue_57s_counts_before():
    before = dict.fromkeys(BEFORE_KINDS_48, 0)
    for _, kind in issue57_rows():
        before[kind] += 1
    assert before == COUNTS_BEFORE_57
    names = [name for name, _ in issue57_rows()] + [c[0] for c in CLI_CASES]
    assert len(set(names)) == len(names)


@pytest.mark.parametrize("case", ISSUE57_CASES, ids=[c[0] for c in ISSUE57_CASES])
def test_issue_57s_commands_are_one_clear_line(case, bad, capsys, monkeypatch, nothing_runs):
    test_each_bad_input_is_one_clear_line_before_any_work(case, bad, capsys, monkeypatch, nothing_runs)


@pytest.mark.parametrize("case", ISSUE57_DEMOS, ids=[c[0] for c in ISSUE57_DEMOS])
def test_issue_57s_demonstrations_are_refused_on_resume_before_any_env(case, bad, capsys, monkeypatch, nothing_runs):
    import egosearch.rl.train

    def built(*args, **kwargs):
        raise AssertionError("an env was built before the demonstrations were refused")

    monkeypatch.setattr(egosearch.rl.train, "make_train_env", built)
    test_each_bad_input_is_one_clear_line_before_any_work(case, bad, capsys, monkeypatch, nothing_runs)


@pytest.mark.parametrize("case", ISSUE57_CONFIGS, ids=[c[0] for c in ISSUE57_CONFIGS])
def test_issue_57s_configs_name_what_is_allowed(case, suite, monkeypatch, capsys):
    test_a_config_naming_no_variant_names_its_key(case, suite, monkeypatch, capsys)


@pytest.mark.parametrize("case", ISSUE57_VARIANT_FILES, ids=[c[0] for c in ISSUE57_VARIANT_FILES])
def test_issue_57s_variant_files_list_the_allowed_keys(case, suite, monkeypatch, capsys):
    stem, _, _, message = case
    monkeypatch.chdir(suite)
    with pytest.raises(SystemExit) as stop:
        checked_variants(config(variant=stem), argv=["compare"], directory=suite / "ablations")
    assert stop.value.code == 1 and capsys.readouterr().err == f"egosearch: error: {message}\n"


def test_a_bare_config_in_a_variant_file_is_an_empty_mapping(tmp_path):
    """`config:` with nothing under it is YAML's null: read as `config: {}`, no override."""
    (tmp_path / "bare.yaml").write_text(ISSUE57_ACCEPTED[0][2].replace("NAME", "bare"))
    assert load_variant("bare", tmp_path).config == {}


@pytest.mark.parametrize("case", ISSUE57_SNAKEMAKE, ids=[c[0] for c in ISSUE57_SNAKEMAKE])
def test_issue_57s_snakemake_rows_are_one_line(case, suite):
    _, _, args, message = case
    rc, lines = snakemake_lines(suite, *args)
    assert rc == 1 and lines == [message]


@pytest.mark.parametrize("case", ISSUE57_ENV_OPTIONS, ids=[c[0] for c in ISSUE57_ENV_OPTIONS])
def test_env_options_that_contradict_their_id_are_one_line(case, monkeypatch):
    """gymnasium's convention: an exception whose message names the option and what is allowed, raised before
    the env (its physics, its sensor) is built."""
    import gymnasium

    import egosearch.searchers.modular
    import egosearch.sim.env

    _, _, env_id, options, message = case

    def built(*args, **kwargs):
        raise AssertionError("the env was built before the bad option was refused")

    monkeypatch.setattr(egosearch.sim.env, "World", built)
    monkeypatch.setattr(egosearch.searchers.modular, "GoalFrontierPolicy", built)
    with pytest.raises(ValueError) as err:
        gymnasium.make(env_id, **options)
    assert str(err.value) == message and "\n" not in str(err.value)


@pytest.mark.parametrize("env_id, options, mask", [
    ("EgoSearch-v0", {"target_memory": True}, "EgoSearchMemory-v0"),
    ("EgoSearchMemory-v0", {"floor_map": True}, "EgoSearchMap-v0"),
    ("EgoSearchNoHead-v0", {"head": False, "target_memory": True, "floor_map": True}, "EgoSearchNoHeadMap-v0"),
])
def test_env_options_that_name_a_registered_observation_are_taken(env_id, options, mask):
    import gymnasium

    from egosearch.envs import env_space_dims

    env = gymnasium.make(f"egosearch:{env_id}", **options)
    assert env.observation_space["mask"].shape == (env_space_dims(mask)["mask"],)
    env.close()


@pytest.mark.skipif(shutil.which("git") is None or not (REPO / ".git").exists(), reason="not a git checkout")
def test_a_smoke_runs_outputs_are_git_ignored():
    """Issue 57: a smoke screen left results/smoke/ untracked; its outputs are plumbing, never stored."""
    paths = ["results/smoke/train/my_lr/seed0/curve.csv", "paper_figs/smoke/table1.md"]
    out = subprocess.run(["git", "check-ignore", *paths], cwd=REPO, capture_output=True, text=True)
    assert out.stdout.split() == paths
    assert subprocess.run(["git", "check-ignore", "-q", "results/cpu/provenance.json"], cwd=REPO).returncode == 1


# --------------------------------------------------------------------------- issue 58: the DAG on a cluster
# The form of issue 57's snakemake rows, with the PATH each runs with: "no slurm" (Slurm's commands taken off
# PATH: a machine that cannot submit), "sinfo lists" (sbatch, squeue and a sinfo listing the partitions debug,
# the default, and gpu: a login node) or "sinfo fails" (the same, its controller not answering); and whether it
# is a dry run (-n) or a real one, stopped before its first job. A job Slurm kills at its time or memory limit
# is one line too, when the run stops (tests/test_cluster.py, tests/test_slurm.py on a real Slurm).
SLURM_PAPER = ["--config", "preset=paper"]
ISSUE58_SNAKEMAKE = [
    ("slurm_without_sbatch", "cryptic", "no slurm", False,
     ["table2", "--executor", "slurm", "--jobs", "2", "--config", "preset=smoke"],
     "egosearch: error: --executor slurm: sbatch is not on PATH here, so no job could be submitted or followed; run "
     "snakemake on a machine that submits to Slurm (a login node, where sbatch, squeue, sinfo are), or leave "
     "--executor slurm (and --workflow-profile profiles/slurm) out to run on this machine"),
    ("slurm_trainings_per_gpu_two", "silent", None, True,
     ["all", "--executor", "slurm", "--jobs", "6", *SLURM_PAPER, "trainings_per_gpu=2"],
     "egosearch: error: config trainings_per_gpu: 2 shares one GPU between trainings on the machine snakemake runs "
     "on; under a cluster executor each training is a job of its own with a whole GPU (gpu=1): leave it auto or 1 "
     "there, or run snakemake with --cores inside one GPU allocation"),
    ("slurm_partition_unknown", "cryptic", "sinfo lists", True,
     ["table2", "--workflow-profile", "profiles/slurm", "--config", "preset=smoke", "--default-resources",
      "slurm_partition=gpuz"],
     "egosearch: error: --default-resources slurm_partition=gpuz: no such partition on this cluster (sinfo lists: "
     "debug, gpu); name one of them, or leave slurm_partition out (each job then goes to the cluster's default "
     "partition, debug)"),
    ("slurm_rule_partition_unknown", "cryptic", "sinfo lists", False,
     ["table2", "--workflow-profile", "profiles/slurm", "--config", "preset=smoke", "--set-resources",
      "table2:slurm_partition=gpus"],
     "egosearch: error: --set-resources table2:slurm_partition=gpus: no such partition on this cluster (sinfo "
     "lists: debug, gpu); name one of them, or leave slurm_partition out (each job then goes to the cluster's "
     "default partition, debug)"),
    ("slurm_controller_unreachable", "cryptic", "sinfo fails", False,
     ["table2", "--workflow-profile", "profiles/slurm", "--config", "preset=smoke"],
     "egosearch: error: --executor slurm: sinfo failed: sinfo: error: Unable to contact slurm controller (connect "
     "failure); run snakemake where Slurm's controller answers (a login node; SLURM_CONF names the cluster's "
     "slurm.conf)"),
]
COUNTS_BEFORE_58 = {"clear": 0, "cryptic": 4, "traceback": 0, "silent": 1, "damage": 0}
"""What the rows did before: the first, third, fourth and fifth ran the DAG and failed at its first submission
(`Job submission failed with exception: [Errno 2] No such file or directory: 'sacct'`; an sbatch error, `invalid
partition specified`, per job; sinfo's DNS lookup); the second ran, each training asking for a share of this
machine's GPU (gpu_slots) instead of a GPU of its own."""
SLURM_NOTICE = "Using workflow specific profile profiles/slurm for setting default command line arguments."


@pytest.fixture(scope="module")
def slurm_paths(tmp_path_factory):
    """PATH for each row: this one without Slurm's commands (a folder of links to everything else on it), or
    with stand-ins for them first."""
    root = tmp_path_factory.mktemp("slurm_paths")
    bare = root / "no_slurm"
    bare.mkdir()
    for folder in os.environ.get("PATH", "").split(os.pathsep):
        if not os.path.isdir(folder):
            continue
        for entry in sorted(os.listdir(folder)):
            if entry in ("sbatch", "squeue", "sinfo", "sacct", "scontrol", "srun", "scancel", "salloc", "sstat"):
                continue
            if not (bare / entry).exists() and os.access(os.path.join(folder, entry), os.X_OK):
                (bare / entry).symlink_to(os.path.join(folder, entry))
    paths = {"no slurm": str(bare)}
    for name, sinfo in (("sinfo lists", "printf 'debug*\\ngpu\\n'"),
                        ("sinfo fails", "echo 'sinfo: error: Unable to contact slurm controller (connect failure)' >&2"
                                        "; exit 1")):
        stand_ins = root / name.replace(" ", "_")
        stand_ins.mkdir()
        for command, body in (("sbatch", "exit 1"), ("squeue", "exit 1"), ("sinfo", sinfo)):
            (stand_ins / command).write_text(f"#!/bin/sh\n{body}\n")
            (stand_ins / command).chmod(0o755)
        paths[name] = f"{stand_ins}{os.pathsep}{os.environ.get('PATH', '')}"
    return paths


def test_issue_58s_counts_before():
    before = dict.fromkeys(BEFORE_KINDS_48, 0)
    for case in ISSUE58_SNAKEMAKE:
        before[case[1]] += 1
    assert before == COUNTS_BEFORE_58
    names = [c[0] for c in ISSUE58_SNAKEMAKE] + [name for name, _ in issue57_rows()] + [c[0] for c in CLI_CASES]
    assert len(set(names)) == len(names)


@pytest.mark.parametrize("case", ISSUE58_SNAKEMAKE, ids=[c[0] for c in ISSUE58_SNAKEMAKE])
def test_issue_58s_cluster_rows_are_one_line_before_any_job(case, suite, slurm_paths):
    _, _, path, dry, args, message = case
    env = {**os.environ, **({"PATH": slurm_paths[path]} if path else {})}
    out = subprocess.run([sys.executable, "-m", "snakemake", *(["-n"] if dry else []), *args], cwd=suite, env=env,
                         capture_output=True, text=True, timeout=600)
    lines = [line for line in (out.stdout + out.stderr).splitlines()
             if line.strip() and line not in (*NOTICES, SLURM_NOTICE)]
    assert out.returncode == 1 and lines == [message], (out.stdout + out.stderr)[-3000:]
    assert not (suite / "results" / "smoke").exists()      # no job ran


# --------------------------------------------------------------------------- issue 73: values that cannot be meant
# The form of issue 57's tables: (id, what it did before the fix, the input, the one line now). Items 5 and 7: a
# run past the documented bounds of its length (egosearch.rl.run_settings.LONG_RUN_BOUNDS; --allow-long, --config
# allow_long=true), a variant whose config contradicts its env id, an env option given twice or to a searcher that
# ignores it, a ';'-separated scenario file, a config shown for a learner the variant does not train with, an
# unknown variant's near name. Item 8: claims pairs (Figure 6's and versus_teacher's first pair), the seed spread's
# and screen's seeds, the budget study, Figure 6's curves and levels.
STEPS_BOUND = "<= 20,000,000 env steps (about 27x Table 2's 750,000), the documented bound"
CURVE_BOUND = ("<= 10,000 episodes a curve point (the most scenarios of one set, `egosearch scenarios --n`), the "
               "documented bound")
DEMOS_BOUND = "<= 100,000 demonstration episodes (about 67x the cpu preset's 1,500), the documented bound"
MEMORY_OFF = ("config: target_memory: false contradicts env_id: EgoSearchMemory-v0, which observes the last-seen "
              "target memory; allowed: target_memory: true or leave it out, or env_id EgoSearch-v0")
# (file stem, before, text, the one line of the workflow's check with variant=stem): in the `suite` and `bad`
# fixtures' files
ISSUE73_VARIANT_FILES = [
    ("long_steps", "silent", HEAD + "config: {total_env_steps: 1000000000000}\n",  # "about 10205001.1 h", then ran
     "ablations/long_steps.yaml: config (on the cpu learner preset): LearnerConfig.total_env_steps=1000000000000 is "
     f"out of range; allowed: {STEPS_BOUND}; --config allow_long=true allows more"),
    ("long_curve", "silent", HEAD + "config: {eval_episodes: 20000}\n",
     "ablations/long_curve.yaml: config (on the cpu learner preset): LearnerConfig.eval_episodes=20000 is out of "
     f"range; allowed: {CURVE_BOUND}; --config allow_long=true allows more"),
    ("long_demos", "silent", HEAD + "config: {demo_episodes: 1000000}\n",
     "ablations/long_demos.yaml: config (on the cpu learner preset): LearnerConfig.demo_episodes=1000000 is out of "
     f"range; allowed: {DEMOS_BOUND}; --config allow_long=true allows more"),
    # variant check said valid, config show said False, and the training observed the memory
    ("memory_off", "silent", HEAD.replace("EgoSearch-v0", "EgoSearchMemory-v0") + "config: {target_memory: false}\n",
     f"ablations/memory_off.yaml: {MEMORY_OFF}"),
    ("modular_off", "silent", HEAD.replace("EgoSearch-v0", "EgoSearchModular-v0")
     + "config: {modular_searcher: false, target_memory: false}\n",
     "ablations/modular_off.yaml: config: modular_searcher: false contradicts env_id: EgoSearchModular-v0, which is "
     "a modular searcher's decision env; allowed: modular_searcher: true or leave it out, or env_id EgoSearch-v0"),
    # a line about target_memory, which the file never set (the cpu preset's), or at smoke the map dropped
    ("map_modular", "cryptic", HEAD.replace("EgoSearch-v0", "EgoSearchMap-v0") + "config: {modular_searcher: true}\n",
     "ablations/map_modular.yaml: config: modular_searcher: true contradicts env_id: EgoSearchMap-v0, which is a "
     "body env (the policy acts at every body step); allowed: leave modular_searcher out, or env_id EgoSearch-v0"),
]
F6 = ["report", "fig6", "results/cpu/train/head_on/seed0/curve.csv"]
LEVEL = "results/cpu/eval_curve/frontier/head_on.csv"
ISSUE73_CASES = [
    ("train_past_the_steps_bound", "silent", ["train", "--variant", "{t}/long_steps.yaml", "--out-dir", "{t}/r73"],
     "egosearch train: error: {t}/long_steps.yaml: config (on the cpu learner preset): "
     f"LearnerConfig.total_env_steps=1000000000000 is out of range; allowed: {STEPS_BOUND}; --allow-long allows more"),
    ("demos_past_the_episodes_bound", "silent",
     ["demos", "--variant", "head_on", "--episodes", "1000000", "--out", "{t}/d73.replay.npz"],
     f"egosearch demos: error: --episodes=1000000 is out of range; allowed: {DEMOS_BOUND}; --allow-long allows more"),
    ("demos_of_a_variant_past_the_episodes_bound", "silent",
     ["demos", "--variant", "{t}/long_demos.yaml", "--out", "{t}/d73.replay.npz"],
     "egosearch demos: error: {t}/long_demos.yaml: config (on the cpu learner preset): "
     f"LearnerConfig.demo_episodes=1000000 is out of range; allowed: {DEMOS_BOUND}; --allow-long allows more"),
    ("evaluate_a_curve_past_the_episodes_bound", "silent",
     ["evaluate", "--curve-of", "{t}/long_curve.yaml", "--policy", "random", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: {t}/long_curve.yaml: config (on the cpu learner preset): "
     f"LearnerConfig.eval_episodes=20000 is out of range; allowed: {CURVE_BOUND}; --allow-long allows more"),
    ("variant_check_a_memory_id_with_the_memory_off", "silent", ["variant", "check", "{t}/memory_off.yaml"],
     f"egosearch variant: error: {{t}}/memory_off.yaml: {MEMORY_OFF}"),
    ("config_show_a_memory_id_with_the_memory_off", "silent",
     ["config", "show", "sac_drq", "--variant", "{t}/memory_off.yaml"],
     f"egosearch config: error: {{t}}/memory_off.yaml: {MEMORY_OFF}"),
    ("train_a_memory_id_with_the_memory_off", "silent",
     ["train", "--variant", "{t}/memory_off.yaml", "--out-dir", "{t}/r73"],
     f"egosearch train: error: {{t}}/memory_off.yaml: {MEMORY_OFF}"),
    ("evaluate_env_option_twice", "silent",  # the last one won
     [*EVALUATE, "--weights", HEAD_ON_ACTOR, "--env-option", "contact_signal=true", "--env-option",
      "contact_signal=false"],
     "egosearch evaluate: error: --env-option contact_signal is given twice (contact_signal=true, "
     "contact_signal=false); give each option once"),
    ("evaluate_env_option_to_the_oracle", "silent",
     [*EVALUATE, "--policy", "oracle", "--env-option", "contact_signal=true"],
     "egosearch evaluate: error: --env-option contact_signal: --policy oracle would ignore it (it reads no "
     "observation option: it acts on the env's own state, not on the policy's observation); leave --env-option out, "
     "or give it with --policy actor"),
    ("evaluate_env_option_to_the_tuned_searcher", "silent",
     [*EVALUATE, "--policy", "frontier_tuned", "--env-option", "contact_signal=false"],
     "egosearch evaluate: error: --env-option contact_signal: --policy frontier_tuned would ignore it (it reads no "
     "observation option: it acts on the env's own state, not on the policy's observation); leave --env-option out, "
     "or give it with --policy actor"),
    ("evaluate_scenarios_separated_by_semicolons", "cryptic",  # "missing columns" listed all 13
     ["evaluate", "--scenarios", "{t}/semicolon.csv", "--policy", "oracle", "--out", "{t}/o.csv"],
     "egosearch evaluate: error: {t}/semicolon.csv is separated by ';', not ','; a scenario CSV is comma-separated, "
     "as `egosearch scenarios` writes it"),
    ("config_show_a_variant_of_another_learner", "silent",  # a SAC+CURL table for a SAC-DrQ training
     ["config", "show", "sac_curl", "--preset", "cpu", "--variant", "head_on"],
     "egosearch config: error: --variant head_on trains algorithm sac_drq at the cpu preset (the preset's "
     "learner), not sac_curl: show that one (egosearch config show sac_drq --preset cpu --variant head_on)"),
    ("train_a_variant_typo", "clear", ["train", "--variant", "hed_on", "--out-dir", "{t}/r73"],
     f"egosearch train: error: variant='hed_on' is unknown (did you mean 'head_on'?); allowed: {ALLOWED} (files in "
     "ablations)"),
    ("fig6_level_given_twice", "silent", [*F6, "--levels", LEVEL, LEVEL, "--out-prefix", "{t}/f6"],
     f"egosearch report: error: --levels: {LEVEL} is given twice; give each searcher's level once"),
    ("fig6_two_levels_of_one_searcher", "silent",
     [*F6, "--levels", LEVEL, "{t}/lv/eval_curve/frontier/head_on.csv", "--out-prefix", "{t}/f6"],
     f"egosearch report: error: --levels: {LEVEL} and {{t}}/lv/eval_curve/frontier/head_on.csv are both frontier's "
     "level; give each searcher's level once"),
    ("fig6_curve_given_twice", "cryptic",  # "a scenario appears twice for the same seed"
     [*F6, F6[2], "--levels", LEVEL, "--out-prefix", "{t}/f6"],
     f"egosearch report: error: the curve files: {F6[2]} is given twice; give each seed's curve once"),
    ("fig6_level_of_another_variants_curve", "silent",
     ["report", "fig6", "results/cpu/train/head_off/seed0/curve.csv", "--levels", LEVEL, "--out-prefix", "{t}/f6"],
     f"egosearch report: error: --levels: {LEVEL} is frontier's level on head_on's curve scenarios, and the curves are "
     "head_off's; give the level of a variant they draw (.../eval_curve/frontier/head_off.csv)"),
    # the command line's learner fields (issue 72's --set)
    ("set_without_a_value", "cryptic",  # "--set: batch_size=None is not an int"
     ["train", "--variant", "head_on", "--set", "batch_size=", "--out-dir", "{t}/r73"],
     "egosearch train: error: --set 'batch_size=': no value after '='; give FIELD=VALUE, e.g. batch_size=<a value>"),
    ("config_show_a_set_out_of_range", "cryptic",  # the range line without naming --set
     ["config", "show", "sac_drq", "--variant", "head_on", "--set", "curriculum_start_radius=20"],
     "egosearch config: error: --set curriculum_start_radius=20: LearnerConfig.curriculum_start_radius=20 is out of "
     "range; allowed: (0, curriculum_end_radius=12.0] m"),
    ("set_given_twice", "clear",
     ["train", "--variant", "head_on", "--set", "batch_size=64", "--set", "batch_size=32", "--out-dir", "{t}/r73"],
     "egosearch train: error: --set: batch_size is given twice (batch_size=64 and batch_size=32); give it once"),
    ("set_the_seed", "clear", ["train", "--variant", "head_on", "--set", "seed=3", "--out-dir", "{t}/r73"],
     "egosearch train: error: --set: seed is set per run (`egosearch train --seed`, the preset's seeds in the "
     "workflow config), not by a variant or --set: leave it out"),
    ("set_another_learner", "clear",
     ["train", "--variant", "head_on", "--set", "algorithm=ppo", "--out-dir", "{t}/r73"],
     "egosearch train: error: --set: algorithm is the variant's learner (its file's config: algorithm); a set changes "
     "the fields of that learner: make a variant to train another one"),
]


def _preset(name: str, **changes) -> dict:
    """The workflow config's ``presets`` with ``changes`` in preset ``name`` (``budget`` merged)."""
    presets = config()["presets"]
    preset = dict(presets[name])
    for key, value in changes.items():
        preset[key] = {**preset.get(key, {}), **value} if key == "budget" else value
    return {"presets": {**presets, name: preset}}


BIG = 2**32
SEED_BOUND = "is out of range; allowed: a training seed <= 2**32 - 1 = 4294967295 (numpy's global seed is 32-bit)"
# (id, before, --config changes, target, the one line): `checked_variants`, as ISSUE48_CONFIGS
ISSUE73_CONFIGS = [
    ("claims_first_pair_classical", "traceback",  # VariantError in common.smk, whatever the target
     {"preset": "smoke", "claims_pairs": [["frontier", "frontier_head_off"]]}, "versus_teacher",
     "config claims_pairs: the first pair ['frontier', 'frontier_head_off'] is Figure 6's and versus_teacher's, which "
     "read its trainings: name variants there (e.g. [head_on, head_off]) and the classical searchers in a later pair"),
    ("claims_pair_backwards", "silent", {"claims_pairs": [["head_off", "head_on"]]}, "versus_teacher",
     "config claims_pairs: ['head_off', 'head_on'] is head_off (head fixed), head_on (head moving); a pair is [head "
     "moving, head fixed]"),
    ("claims_pair_of_one_head", "silent", {"claims_pairs": [["head_on", "head_on_25px"]]}, "behaviour",
     "config claims_pairs: ['head_on', 'head_on_25px'] is head_on (head moving), head_on_25px (head moving); a pair "
     "is [head moving, head fixed]"),
    ("claims_classical_pair_backwards", "silent",
     {"claims_pairs": [["head_on", "head_off"], ["frontier_head_off", "frontier"]]}, "behaviour",
     "config claims_pairs: ['frontier_head_off', 'frontier'] is frontier_head_off (head fixed), frontier (head "
     "moving); a pair is [head moving, head fixed]"),
    ("screen_seeds_past_numpys_seed", "cryptic",  # the DAG ran; the fifth training failed in its job
     {"variant": "head_off", "screen_seed": BIG - 1, "screen_seeds": 5}, "screen",
     f"config screen_seed: {BIG - 1} with screen_seeds=5 trains seeds up to {BIG + 3}, which {SEED_BOUND}"),
    ("preset_seed_past_numpys_seed", "cryptic", _preset("smoke", seeds=[BIG]), "all",
     f"config presets/smoke/seeds: {BIG} {SEED_BOUND}"),
    ("spread_seed_past_numpys_seed", "cryptic", _preset("cpu", spread_seeds=[0, BIG]), "seed_spread",
     f"config presets/cpu/spread_seeds: {BIG} {SEED_BOUND}"),
    ("budget_seed_past_numpys_seed", "cryptic", _preset("cpu", budget={"seeds": [BIG]}), "budget",
     f"config presets/cpu/budget/seeds: {BIG} {SEED_BOUND}"),
    ("budget_reference_among_its_settings", "silent",  # its seed-0 run stood in for the setting's, unsaid
     _preset("cpu", budget={"variants": ["head_on_from_scratch", "head_on_25px"]}), "budget",
     "config presets/cpu/budget/variants: 'head_on_from_scratch' is the study's own setting (budget/reference), "
     "read against itself; leave it out of variants (its runs are the preset's seeds already)"),
    ("budget_reference_variant_among_the_settings", "silent",
     {"preset": "smoke", **_preset("smoke", budget={"variants": ["head_on"]})}, "budget",
     "config presets/smoke/budget/variants: 'head_on' is the study's own setting (reference_variant), read against "
     "itself; leave it out of variants (its runs are the preset's seeds already)"),
]
COUNTS_BEFORE_73 = {"clear": 4, "cryptic": 10, "traceback": 2, "silent": 27, "damage": 0}
"""What the rows above did before the fix (with the Slurm and read-only rows below); after it each is one clear
line before any work."""


def test_issue_73s_counts_before():
    rows = ([c[:2] for c in ISSUE73_CASES] + [c[:2] for c in ISSUE73_CONFIGS] + [c[:2] for c in ISSUE73_VARIANT_FILES]
            + [c[:2] for c in ISSUE73_SNAKEMAKE] + [("results_read_only", "traceback"),
                                                   ("claims_pairs_a_preset_overrides", "silent")])
    before = dict.fromkeys(BEFORE_KINDS_48, 0)
    for _, kind in rows:
        before[kind] += 1
    assert before == COUNTS_BEFORE_73
    names = [name for name, _ in rows + issue57_rows()] + [c[0] for c in CLI_CASES + ISSUE58_SNAKEMAKE]
    assert len(set(names)) == len(names)


@pytest.mark.parametrize("case", ISSUE73_CASES, ids=[c[0] for c in ISSUE73_CASES])
def test_issue_73s_commands_are_one_clear_line(case, bad, capsys, monkeypatch, nothing_runs):
    monkeypatch.delenv("EGOSEARCH_ALLOW_LONG", raising=False)
    level = bad / "lv/eval_curve/frontier/head_on.csv"
    if not level.exists():
        level.parent.mkdir(parents=True)
        shutil.copy2(REPO / LEVEL, level)
    test_each_bad_input_is_one_clear_line_before_any_work(case, bad, capsys, monkeypatch, nothing_runs)


@pytest.mark.parametrize("case", ISSUE73_CONFIGS, ids=[c[0] for c in ISSUE73_CONFIGS])
def test_issue_73s_configs_are_one_line(case, suite, monkeypatch, capsys):
    test_a_config_naming_no_variant_names_its_key(case, suite, monkeypatch, capsys)


@pytest.mark.parametrize("case", ISSUE73_VARIANT_FILES, ids=[c[0] for c in ISSUE73_VARIANT_FILES])
def test_issue_73s_variant_files_are_one_line_in_the_workflow(case, suite, monkeypatch, capsys):
    monkeypatch.delenv("EGOSEARCH_ALLOW_LONG", raising=False)
    test_issue_57s_variant_files_list_the_allowed_keys(case, suite, monkeypatch, capsys)


def test_claims_pairs_a_preset_overrides_are_one_line(suite, monkeypatch, capsys):
    """`--config claims_pairs=...` at the cpu preset, which names its own: they were ignored without a word."""
    monkeypatch.chdir(suite)
    pairs = [["head_on", "head_off"]]
    with pytest.raises(SystemExit) as stop:
        checked_variants(config(claims_pairs=pairs), argv=["behaviour"], directory=suite / "ablations",
                         command_line={"claims_pairs": pairs})
    assert stop.value.code == 1 and capsys.readouterr().err == (
        "egosearch: error: config claims_pairs: the cpu preset names its own (presets/cpu/claims_pairs in "
        "egosearch/workflow/config.yaml), which the run reads instead of the top level's; edit that one, or run "
        "another preset\n")
    checked_variants(config(claims_pairs=pairs, preset="smoke"), argv=["behaviour"], directory=suite / "ablations",
                     command_line={"claims_pairs": pairs})


def test_a_long_run_is_taken_when_allowed(suite, bad, monkeypatch, capsys):
    """--allow-long, --config allow_long=true (as Snakemake hands it over: a string) and the environment the
    workflow gives its jobs each allow what the bounds refuse."""
    monkeypatch.delenv("EGOSEARCH_ALLOW_LONG", raising=False)
    monkeypatch.chdir(suite)
    assert "long_steps" in checked_variants(config(variant="long_steps", allow_long="true"), argv=["compare"],
                                            directory=suite / "ablations")
    monkeypatch.chdir(REPO)
    long_steps = str(bad / "long_steps.yaml")
    assert main(["variant", "check", long_steps, "--preset", "cpu", "--allow-long"]) == 0
    monkeypatch.setenv("EGOSEARCH_ALLOW_LONG", "1")
    assert main(["variant", "check", long_steps, "--preset", "cpu"]) == 0
    assert capsys.readouterr().out.count("valid at the cpu learner preset") == 2


def test_a_stored_variant_is_within_the_bounds(monkeypatch):
    """Every variant the suite ships trains within the documented bounds at every preset it runs at."""
    from egosearch.variants import check_learner_config

    monkeypatch.delenv("EGOSEARCH_ALLOW_LONG", raising=False)
    for name in variant_names(REPO / "ablations"):
        check_learner_config(load_variant(name, REPO / "ablations"), "cpu")


@pytest.mark.parametrize("doc, first", [
    ("Paper 4.1: 1.0, i.e. the camera height is drawn from [1.0, 1.8] m. Otherwise more.",
     "Paper 4.1: 1.0, i.e. the camera height is drawn from [1.0, 1.8] m."),
    ('Paper eq. 2 text: "distance" = r_d. "progress" = the decrease.', 'Paper eq. 2 text: "distance" = r_d.'),
    ("PIRLNav (Ramrakhya et al. 2023: the critic first. Then the actor): the first updates. More.",
     "PIRLNav (Ramrakhya et al. 2023: the critic first. Then the actor): the first updates."),
    ("A rate of 0.5 per step. The rest.", "A rate of 0.5 per step."),
    ("No full stop", "No full stop."),
], ids=["i.e.", "eq.", "et al. in brackets", "decimal point", "no stop"])
def test_config_show_gives_a_fields_whole_first_sentence(doc, first):
    from egosearch.rl.config import first_sentence

    assert first_sentence(doc) == first


def test_config_show_cuts_no_field_at_an_abbreviation():
    from egosearch.rl.config import config_sources

    for algorithm in ("sac_drq", "sac_curl"):
        for row in config_sources(algorithm, "cpu"):
            assert not row["doc"].endswith(("i.e.", "e.g.", "eq.", "al.")), row


# (id, before, the snakemake arguments after -n, how the profile copy is spoiled, the one line): the Slurm profile,
# copied into the suite and edited, as tests/test_cluster.py runs it
ISSUE73_SNAKEMAKE = [
    ("slurm_mem_mb_a_word", "cryptic",  # "Exception ignored in atexit callback ... ResourceConversionError", exit 0
     ["table2", "--workflow-profile", "profiles/slurm73", "--config", "preset=smoke"],
     ("mem_mb: 1000", "mem_mb: lots"),
     "egosearch: error: --default-resources mem_mb=lots: not a number; allowed: a number of megabytes > 0 (e.g. "
     "mem_mb=1000)"),
    ("slurm_runtime_zero", "silent",  # the plan's sbatch had no -t
     ["table2", "--workflow-profile", "profiles/slurm73", "--config", "preset=smoke"], ("runtime: 30", "runtime: 0"),
     "egosearch: error: --default-resources runtime=0: a job would ask for no time limit (sbatch without -t); "
     "allowed: a number of minutes > 0"),
    ("slurm_profile_under_the_default_one", "silent",  # profiles/default's jobs: 2 capped the 100
     ["table2", "--profile", "profiles/slurm73", "--config", "preset=smoke"], None,
     "egosearch: error: --profile profiles/slurm73: Snakemake reads the workflow profile profiles/default on top of "
     "it, and its jobs: 2 overrides the jobs: 100 of profiles/slurm73; use --workflow-profile profiles/slurm73 "
     "instead (it replaces profiles/default; docs/running.md)"),
]


@pytest.mark.parametrize("case", ISSUE73_SNAKEMAKE, ids=[c[0] for c in ISSUE73_SNAKEMAKE])
def test_issue_73s_slurm_rows_are_one_line_before_any_job(case, suite, slurm_paths):
    _, _, args, spoil, message = case
    profile = suite / "profiles" / "slurm73"
    shutil.rmtree(profile, ignore_errors=True)
    shutil.copytree(REPO / "profiles" / "slurm", profile)
    if spoil:
        text = (profile / "config.yaml").read_text()
        assert spoil[0] in text
        (profile / "config.yaml").write_text(text.replace(spoil[0], spoil[1]))
    out = subprocess.run([sys.executable, "-m", "snakemake", "-n", *args], cwd=suite, capture_output=True, text=True,
                         timeout=600, env={**os.environ, "PATH": slurm_paths["no slurm"]})
    lines = [line for line in (out.stdout + out.stderr).splitlines() if line.strip() and line not in NOTICES
             and not line.startswith("Using ")]
    assert out.returncode == 1 and lines == [message], (out.stdout + out.stderr)[-3000:]


def test_the_resource_check_passes_what_snakemake_reads():
    from egosearch.workflow.cluster import resource_problem

    assert resource_problem(["mem_mb=1000", "runtime=30", "tmpdir=system_tmpdir", "slurm_partition=gpu"], {}) is None
    assert resource_problem(["mem_mb=2 * attempt * 1000", "runtime='1h'"], {"train": {"runtime": 720}}) is None
    assert resource_problem([], {"train": {"mem_mb": "-5"}}) == (
        "--set-resources train:mem_mb=-5: a job would ask for no memory (or disk) at all; allowed: a number of "
        "megabytes > 0")


def test_a_profile_given_with_the_workflow_profile_or_clashing_nowhere_passes(tmp_path):
    from egosearch.workflow.cluster import profile_mix_problem

    (tmp_path / "default").mkdir()
    (tmp_path / "default" / "config.yaml").write_text("jobs: 2\nrerun-incomplete: true\n")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "config.yaml").write_text("rerun-incomplete: true\nlatency-wait: 5\n")
    default = tmp_path / "default"
    assert profile_mix_problem([str(tmp_path / "mine")], None, default) is None
    assert profile_mix_problem(["profiles/slurm"], "profiles/slurm", default) is None
    assert profile_mix_problem(None, None, default) is None


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs /proc (a location nobody may write in)")
def test_an_output_folder_nobody_may_write_in_is_one_line(tmp_path):
    """Tried by making a file there: root may write in a folder chmod'ed read-only, never in /proc (nor on a
    read-only mount, the test below)."""
    from egosearch.workflow.check import unwritable_outputs_line

    assert unwritable_outputs_line([tmp_path / "results/smoke/x.csv"]) is None
    line = unwritable_outputs_line(["/proc/results/smoke/scenarios/x.csv", tmp_path / "y.csv"])
    assert line.startswith("refusing to start: /proc cannot be written (") and line.endswith(
        "), and this run writes /proc/results/smoke/scenarios/x.csv there; make it writable, or run from a checkout "
        "that is")


def test_a_read_only_results_folder_is_one_line_before_the_first_job(suite, tmp_path):
    """results/ on a read-only mount (root writes anywhere else): the run used to stop in its first job with
    Snakemake's "Failed to create output directory ... OSError: [Errno 30] Read-only file system"."""
    results = suite / "results"
    results.mkdir(exist_ok=True)
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(results)],
                             capture_output=True, text=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a read-only folder here: {mounted.stderr.strip()}")
    try:
        target = "results/smoke/scenarios/kitchen_living/everywhere/h1.05.csv"
        out = subprocess.run([sys.executable, "-m", "snakemake", "--cores", "1", target, "--config", "preset=smoke"],
                             cwd=suite, capture_output=True, text=True, timeout=600)
    finally:
        subprocess.run(["umount", str(results)], check=True)
    text = out.stdout + out.stderr
    assert out.returncode == 1 and "Traceback" not in text and "Errno 30" not in text, text[-3000:]
    assert text.rstrip().splitlines()[-1] == (
        f"refusing to start: results cannot be written (Read-only file system), and this run writes {target} there; "
        "make it writable, or run from a checkout that is")
    assert "localrule scenarios:" not in text  # no job started


def test_a_dry_run_with_nothing_to_do_prints_no_sbatch_plan(slurm_paths):
    """A target whose files are stored: no job, so no "What each job asks sbatch for" block (it listed every job
    of the DAG, none of which would run)."""
    out = subprocess.run([sys.executable, "-m", "snakemake", "-n", "table2", "--workflow-profile", "profiles/slurm"],
                         cwd=REPO, capture_output=True, text=True, timeout=600,
                         env={**os.environ, "PATH": slurm_paths["no slurm"]})
    text = out.stdout + out.stderr
    assert out.returncode == 0 and "Nothing to be done" in text, text[-3000:]
    assert "asks sbatch for" not in text
