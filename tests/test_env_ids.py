"""The env's options resolved in one place (egosearch.envs): every id maps onto its options and back, every
stored run's recorded id and config still resolve, and gymnasium finds the ids with no other import."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from egosearch.envs import ALL_ENV_IDS, EnvOptions, env_options, env_space_dims, observed_env_id
from egosearch.rl.run_files import saved_config

REPO = Path(__file__).resolve().parent.parent
STORED_RUNS = sorted(REPO.glob("results/*/train/*/seed*/config.json"))


def test_every_id_is_its_options_and_back():
    for env_id in ALL_ENV_IDS:
        assert env_options(env_id).env_id == env_id
    assert EnvOptions(head=False, target_memory=True).env_id == "EgoSearchNoHeadMemory-v0"
    assert EnvOptions(floor_map=True).env_id == "EgoSearchMap-v0"  # the map comes with the memory
    assert EnvOptions(head=False, modular=True).env_id == "EgoSearchNoHeadModular-v0"
    with pytest.raises(ValueError, match="no target memory"):
        _ = EnvOptions(modular=True, target_memory=True).env_id
    with pytest.raises(ValueError, match="not one of egosearch's"):
        env_options("EgoSearchModularMemory-v0")


def test_the_config_fields_choose_the_observed_id_by_options():
    assert observed_env_id("EgoSearch-v0", True) == "EgoSearchMemory-v0"
    assert observed_env_id("EgoSearchNoHead-v0", False, modular_searcher=True) == "EgoSearchNoHeadModular-v0"
    assert observed_env_id("EgoSearchNoHeadMap-v0", True) == "EgoSearchNoHeadMap-v0"
    assert observed_env_id("EgoSearchModular-v0", True) == "EgoSearchModular-v0"  # a decision env stays
    # the modular decision env's observation is wider than its body env's by the map, its action narrower
    assert env_space_dims("EgoSearchModular-v0")["mask"] > env_space_dims("EgoSearch-v0")["mask"]
    assert env_space_dims("EgoSearchNoHeadModular-v0")["action"] == 2


@pytest.mark.skipif(not STORED_RUNS, reason="no stored runs in this checkout")
def test_every_stored_run_resolves_whatever_id_it_recorded():
    """A stored run's id maps onto options that agree with its config's fields (those recorded before the
    fields existed read from the id), and resolving it again with them leaves it as it is: nothing stored
    depends on a substring. (A variant may name a *Memory-v0 id itself, with the field off.)"""
    seen = set()
    for path in STORED_RUNS:
        saved = json.loads(path.read_text(encoding="utf-8"))
        env_id = saved["env_id"]
        options = env_options(env_id)  # raises for an id egosearch does not know
        config = saved_config(saved)
        assert options.modular == bool(config["modular_searcher"]), path
        assert options.target_memory or not config["target_memory"], path
        assert observed_env_id(env_id, config["target_memory"], config["modular_searcher"]) == env_id, path
        seen.add(env_id)
    assert {"EgoSearch-v0", "EgoSearchNoHead-v0", "EgoSearchModular-v0"} <= seen


def _in_a_fresh_interpreter(code: str) -> str:
    """What ``code`` prints in a new Python process (nothing of egosearch imported before it)."""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_gymnasium_finds_the_ids_after_importing_only_gymnasium():
    code = ("import gymnasium\n"
            "env = gymnasium.make('egosearch:EgoSearch-v0', layout='studio', target_memory=True)\n"
            "obs, info = env.reset(seed=0)\n"
            "print(obs['mask'].shape)\n"
            "import egosearch.report, sys\n"
            "print('egosearch.envs' in sys.modules)\n")
    shape, registered = _in_a_fresh_interpreter(code).split()[-2:]
    assert registered == "True"
    assert shape == f"({env_space_dims('EgoSearchMemory-v0')['mask']},)"  # the option took effect


def test_import_egosearch_envs_registers_every_id_without_the_physics():
    code = ("import sys, egosearch.envs\n"
            "from gymnasium.envs.registration import registry\n"
            "missing = [i for i in egosearch.envs.ALL_ENV_IDS if i not in registry]\n"
            "heavy = [m for m in ('pybullet', 'torch', 'egosearch.sim.env') if m in sys.modules]\n"
            "assert not missing and not heavy, (missing, heavy)\n")
    _in_a_fresh_interpreter(code)


def _readme_line() -> str:
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    return readme.split("```python\n", 1)[1].split("\n```", 1)[0]


@pytest.mark.slow
def test_the_readmes_line_runs_from_the_folder_above_a_clone_named_egosearch(tmp_path):
    """Issue 57: run from the folder that holds a clone named ``egosearch`` (or from a script saved there),
    Python finds the clone's folder on sys.path first. Under an editable install that imports the package
    through a finder asked after sys.path, that folder became an empty namespace package and gymnasium found
    no ids. The clone here is a copy of what an install reads, installed editable into a venv as the README
    installs it (no dependencies: the venv sees this interpreter's)."""
    clone = tmp_path / "egosearch"
    clone.mkdir()
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy2(REPO / name, clone / name)
    shutil.copytree(REPO / "egosearch", clone / "egosearch",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(venv)], check=True,
                   timeout=120)
    python = str(venv / "bin" / "python")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    install = subprocess.run([sys.executable, "-m", "pip", "--python", python, "install", "-q", "--no-deps",
                              "--no-build-isolation", "--no-index", "-e", str(clone)], capture_output=True, text=True,
                             env=env, timeout=600)
    assert install.returncode == 0, install.stderr[-2000:]
    line = _readme_line()
    (tmp_path / "try_egosearch.py").write_text(line + "\nimport egosearch; print(egosearch.__file__)\n")
    runs = {"the folder above the clone": ([python, "-c", line + "; import egosearch; print(egosearch.__file__)"],
                                           tmp_path),
            "a script saved there": ([python, "try_egosearch.py"], tmp_path),
            "the clone": ([python, "-c", line + "; import egosearch; print(egosearch.__file__)"], clone)}
    for where, (cmd, cwd) in runs.items():
        out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env, timeout=300)
        assert out.returncode == 0, f"from {where}: {out.stderr[-1500:]}"
        assert out.stdout.split()[-1] == str(clone / "egosearch" / "__init__.py"), where
