"""Issue 72 items 2 and 3: `egosearch config show` is the whole truth (the variant's env, the curriculum's radii,
each docstring whole with --full, one default per field), and config fields set on the command line
(`egosearch train --set`, `snakemake --config set=...`) are checked as a variant file's, recorded and held on resume."""

from __future__ import annotations

import ast
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from egosearch.cli import main
from egosearch.rl.config import LearnerConfig, field_defaults, field_docs, load_config
from egosearch.rl.run_files import CheckpointError
from egosearch.rl.train import train
from egosearch.variants import VariantError, load_variant, parse_set, resolve_variant

REPO = Path(__file__).resolve().parent.parent
TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_rl_fake_env import FAKE_ENV_ID, register_fake_envs  # noqa: E402

register_fake_envs()


def show(capsys, *args: str) -> list[str]:
    assert main(["config", "show", *args]) == 0
    return capsys.readouterr().out.splitlines()


def test_config_show_prints_the_variants_env_and_the_curriculum_radii(capsys):
    variant = load_variant("head_on")
    out = show(capsys, "sac_drq", "--preset", "cpu", "--variant", "head_on")
    env_line = next(line for line in out if line.startswith("env_id "))
    observed = resolve_variant("head_on", "cpu").env_id
    assert variant.env_id in env_line and observed in env_line and "variant head_on" in env_line
    train_line = next(line for line in out if line.startswith("train_env "))
    assert all(f"{key}={value!r}" in train_line for key, value in variant.train_env.items())
    # the curriculum's radii, module constants before, are fields with today's values
    rows = {line.split()[0]: line.split()[1:3] for line in out[4:]}
    assert rows["curriculum_start_radius"] == ["1.0", "default"]
    assert rows["curriculum_end_radius"] == ["12.0", "default"]
    # without a variant it says where env_id and train_env come from
    assert "give --variant" in show(capsys, "sac_drq")[1]


def test_the_curriculum_radii_are_fields_and_stored_runs_load_without_them():
    cfg = load_config("cpu", {"algorithm": "sac_drq", "curriculum_steps": 100})
    assert (cfg.curriculum_start_radius, cfg.curriculum_end_radius) == (1.0, 12.0)
    assert cfg.start_radius(0) == 1.0 and cfg.start_radius(50) == 6.5 and cfg.start_radius(100) is None
    narrow = load_config("cpu", {"algorithm": "sac_drq", "curriculum_steps": 100, "curriculum_end_radius": 3.0})
    assert narrow.start_radius(50) == 2.0
    with pytest.raises(ValueError, match="curriculum_start_radius=5.0 is out of range"):
        load_config("cpu", {"curriculum_start_radius": 5.0, "curriculum_end_radius": 3.0})
    stored = REPO / "results/cpu/train/head_off_imitation_finetune/seed0/config.json"
    if stored.exists():  # a pair kept under its name, recorded before the fields: loads at their defaults
        recorded = json.loads(stored.read_text())["config"]
        assert "curriculum_end_radius" not in recorded
        assert LearnerConfig.from_stored(recorded).curriculum_end_radius == 12.0


def test_full_prints_each_fields_whole_docstring(capsys):
    out = show(capsys, "sac_drq", "--full")
    text = " ".join(" ".join(out).split())
    docs = field_docs()
    for name in LearnerConfig(algorithm="sac_drq").to_dict():
        assert f"{name} = " in text and docs[name] in text, name
    # without --full: the first sentence, not cut at "eq." nor "et al."
    short = {line.split()[0]: line for line in show(capsys, "sac_drq")[3:]}
    assert short["train_distance_reward"].endswith("r_d is minus the distance to the target while it is seen.")
    assert "Ramrakhya et al. 2023" in short["critic_warmup_updates"]


SECOND_DEFAULT = re.compile(r"""(?:getattr\(\s*[\w.]+,\s*|\.get\(\s*)["'](\w+)["']\s*,\s*([^)]+)\)""")
NOT_A_SECOND_DEFAULT = {
    ("egosearch/rl/actor.py", "crop_size"): "an actor file's arch: no crop_size reads the whole frame",
    ("egosearch/rl/config.py", "aug_pad"): "Table 2's row for a learner without the shift: no shift",
    ("egosearch/report/gpu.py", "cuda_graph"): "a GPU record's overrides: not overridden",
    ("egosearch/rl/bench_learner.py", "init_steps"): "the benchmark's own short-run value",
}
"""Reads of a field's name with a fallback that are not a config default (what each fallback means)."""


def is_literal(text: str) -> bool:
    """Whether ``text`` is a literal value (a second default), not an expression (the field's declared default
    read through ``field_defaults()``, a recorded config's value)."""
    try:
        ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return False
    return True


def test_each_config_field_has_one_default():
    """A field's default is its declaration's alone: no `getattr(cfg, "f", 1)` or `.get("f", 0)` restating it, and
    no workflow config key restating a learner field (issue 72: demo_episodes, dagger_rounds, obs_downsample)."""
    names = set(field_defaults())
    found = []
    for path in sorted(REPO.joinpath("egosearch").rglob("*.py")):
        rel = str(path.relative_to(REPO))
        for match in SECOND_DEFAULT.finditer(path.read_text(encoding="utf-8")):
            field, fallback = match.group(1), match.group(2).strip()
            if field in names and (rel, field) not in NOT_A_SECOND_DEFAULT and is_literal(fallback):
                found.append(f"{rel}: {match.group(0)}")
    assert not found, found
    workflow = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())
    assert not set(workflow) & names and not any(set(p) & names for p in workflow["presets"].values())


def test_set_is_checked_as_a_variant_files_value():
    assert parse_set(["batch_size=64", "actor_lr=1e-4", "target_memory=true", "demo_teacher=frontier"]) == {
        "batch_size": 64, "actor_lr": 1e-4, "target_memory": True, "demo_teacher": "frontier"}
    assert parse_set("batch_size=64,actor_lr=1e-4") == {"batch_size": 64, "actor_lr": 1e-4}
    typo = "--set: 'batch_siz' is not a LearnerConfig field (did you mean batch_size?)"
    for items, said in [(["batch_siz=64"], typo),
                        (["batch_size=abc"], "--set: batch_size='abc' is not an int"),
                        (["batch_size"], "--set 'batch_size': give FIELD=VALUE"),
                        (["seed=3"], "--set: seed is set per run"),
                        (["algorithm=ppo"], "--set: algorithm is the variant's learner"),
                        (["actor_lr=nan"], "--set: actor_lr=nan is not a finite number"),
                        (["batch_size=1", "batch_size=2"], "--set: batch_size is given twice")]:
        with pytest.raises(VariantError) as err:
            parse_set(items)
        assert str(err.value).startswith(said) and "\n" not in str(err.value)
    with pytest.raises(VariantError, match=r"^--set batch_size=-1: LearnerConfig.batch_size=-1 is out of range"):
        resolve_variant("head_on", "smoke", {"seed": 0}, {"batch_size": -1})
    resolved = resolve_variant("head_on", "smoke", {"seed": 0}, {"batch_size": 8})
    assert resolved.config.batch_size == 8 and resolved.set_overrides == {"batch_size": 8}


def test_config_show_names_each_values_source(capsys):
    out = show(capsys, "sac_drq", "--variant", "head_on_contact_signal", "--set", "batch_size=64",
               "--set", "contact_signal=false")
    assert out[0].startswith("sac_drq at preset cpu with variant head_on_contact_signal and --set "
                             "batch_size=64,contact_signal=False: ")
    rows = {line.split()[0]: line.split()[1:3] for line in out[4:]}
    assert rows["batch_size"] == ["64", "--set"] and rows["contact_signal"] == ["False", "--set"]
    assert rows["total_env_steps"] == ["200000", "preset"] and rows["gamma"] == ["0.99", "default"]


def test_a_bad_set_on_the_command_line_is_one_line(tmp_path, capsys):
    assert main(["train", "--variant", "head_on", "--preset", "smoke", "--set", "batch_siz=64",
                 "--out-dir", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == ("egosearch train: error: --set: 'batch_siz' is not a LearnerConfig field (did you mean "
                   "batch_size?)")
    assert main(["train", "--variant", "head_on", "--preset", "smoke", "--set", "batch_size=0",
                 "--out-dir", str(tmp_path / "run")]) == 2
    assert capsys.readouterr().err.strip().startswith("egosearch train: error: --set batch_size=0: LearnerConfig.")
    assert not (tmp_path / "run").exists()


class Interrupt(Exception):
    pass


def stop_at(n: int):
    def hook(step: int) -> None:
        if step == n:
            raise Interrupt(step)
    return hook


def test_set_is_recorded_and_a_resume_refuses_another(tmp_path):
    cfg = load_config("smoke", {"device": "cpu", "num_threads": 1, "batch_size": 16})
    with pytest.raises(Interrupt):
        train(FAKE_ENV_ID, cfg, tmp_path, variant="v", progress=False, on_step=stop_at(160),
              set_overrides={"batch_size": 16})
    assert json.loads((tmp_path / "config.json").read_text())["set"] == {"batch_size": 16}
    # the same config without the --set that made it: refused, in one line, naming --set
    with pytest.raises(CheckpointError) as err:
        train(FAKE_ENV_ID, cfg, tmp_path, variant="v", progress=False)
    assert "was trained with --set batch_size=16, not none" in str(err.value) and "\n" not in str(err.value)
    with pytest.raises(CheckpointError, match="trained with --set batch_size=16, not batch_size=16,gamma=0.9"):
        train(FAKE_ENV_ID, load_config("smoke", {"device": "cpu", "num_threads": 1, "batch_size": 16, "gamma": 0.9}),
              tmp_path, variant="v", progress=False, set_overrides={"batch_size": 16, "gamma": 0.9})
    # the same --set resumes, a resumable field's too (num_threads is the machine's, not the run's)
    done = train(FAKE_ENV_ID, cfg, tmp_path, variant="v", progress=False,
                 set_overrides={"batch_size": 16, "num_threads": 1})
    assert done["set"] == {"batch_size": 16, "num_threads": 1}
    assert json.loads((tmp_path / "done.json").read_text())["set"] == {"batch_size": 16, "num_threads": 1}
    with pytest.raises(CheckpointError, match="finished run .* was trained with --set batch_size=16, not none"):
        train(FAKE_ENV_ID, cfg, tmp_path, variant="v", progress=False)


def test_snakemake_hands_the_set_to_the_trainings_and_refuses_stored_ones():
    """`snakemake --config set=...`: checked before the DAG (a field), against each training of the DAG (its range,
    its learner) and its stored trainings (none may have another set); the trainings it runs get --set."""
    def dry(*args):
        return subprocess.run([sys.executable, "-m", "snakemake", "-n", "-p", *args], cwd=REPO, capture_output=True,
                              text=True, timeout=600)

    smoke = "results/smoke/train/head_on/seed0/actor.pt"
    if (REPO / smoke).exists():
        pytest.skip("a smoke training is stored in this checkout")
    planned = dry(smoke, "--config", "preset=smoke", "set=batch_size=16,actor_lr=1e-4")
    assert planned.returncode == 0, planned.stderr
    assert "--set batch_size=16 --set actor_lr=0.0001 > results/smoke/logs/train/head_on/seed0.log" in planned.stdout
    typo = dry(smoke, "--config", "preset=smoke", "set=batch_siz=16")
    assert typo.returncode == 1 and typo.stderr.strip().splitlines()[-1] == (
        "egosearch: error: config set: 'batch_siz' is not a LearnerConfig field (did you mean batch_size?)")
    out_of_range = dry(smoke, "--config", "preset=smoke", "set=batch_size=-1")
    assert out_of_range.returncode == 1 and out_of_range.stderr.strip().splitlines()[-1].startswith(
        "egosearch: error: config set=batch_size=-1: variant head_on: LearnerConfig.batch_size=-1 is out of range")
    stored = "results/cpu/train/head_on/seed0/actor.pt"
    if (REPO / stored).exists():
        reused = dry(stored, "--config", "set=batch_size=64")
        assert reused.returncode == 1 and "the plan reads the stored training results/cpu/train/head_on/seed0, " \
            "trained with set none" in reused.stderr
