"""Extending the suite (docs/extending.md): the four extensions a newcomer makes (a classical searcher, a field
of SAC-DrQ, an observation option of the env, a learner) are each one file, its registration line and its own
test. This test makes all four, as docs/extending.md says, in a temporary copy of the repository (the toys are in
tests/extensions/), then runs the suite's own checks there: lint, the layout, every registry's and config's
tests, the env options', the pinned updates, the bad-input lines, the README against the stored results. Nothing
else is edited; a check that needs another place edited fails here."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TOYS = Path(__file__).parent / "extensions"

COPIED = ("egosearch", "tests", "docs", "ablations", "profiles", "pyproject.toml", "setup.py", "Snakefile",
          "mkdocs.yml", "README.md")
"""What the copy holds of the repository; the stored results and figures are linked, read only."""
LINKED = ("results", "paper_figs")

NEW_FILES = {
    "toy_spin.py": "egosearch/searchers/toy_spin.py",
    "check_toy_spin.py": "tests/test_toy_spin.py",
    "toy_step_clock.py": "egosearch/sim/toy_step_clock.py",
    "check_toy_step_clock.py": "tests/test_toy_step_clock.py",
    "toy_bc.py": "egosearch/rl/toy_bc.py",
    "check_toy_bc.py": "tests/test_toy_bc.py",
    "check_toy_field.py": "tests/test_toy_field.py",
}
"""Each extension's file and its own test: toy in tests/extensions/ -> where the copy gets it."""

REGISTRATIONS = {
    "egosearch/searchers/searcher_registry.py": '''
register("toy_spin", "egosearch.searchers.toy_spin:ToySpin", env_id="EgoSearchNoHead-v0", head=False,
         label="toy searcher that only turns", what="turns on the spot", bound=True)
''',
    "egosearch/sim/observation_options.py": '''
register("toy_step_clock", "egosearch.sim.toy_step_clock:ToyStepClock",
         "egosearch.sim.toy_step_clock:ToyStepClockSettings")
''',
    "egosearch/rl/learner_registry.py": '''
register("toy_bc", "toy BC", "egosearch.rl.toy_bc:ToyBcAgent",
         {"toy-bc-actor-v1": "egosearch.rl.toy_bc:load_actor_net"}, settings="egosearch.rl.toy_bc:ToyBcSettings")
''',
}
"""Each registry's new line, appended after its own registrations."""

FIELD_FILE, FIELD_ANCHOR = "egosearch/rl/sac_drq_settings.py", "    def own_checks(self, bad: Complaint) -> None:\n"
"""The SAC-DrQ field goes into SAC-DrQ's settings class, before its checks."""

SUITE_CHECKS = ("tests/test_toy_spin.py", "tests/test_toy_step_clock.py", "tests/test_toy_bc.py",
                "tests/test_toy_field.py", "tests/test_layout.py", "tests/test_learner_config.py",
                "tests/test_rl_registry.py", "tests/test_searcher_registry.py", "tests/test_env_options.py",
                "tests/test_learner_updates_pinned.py", "tests/test_bad_input.py", "tests/test_readme.py",
                "tests/test_variants.py")
"""The suite's own checks that read what an extension touches (each toy's test first)."""


def make_copy(dest: Path) -> None:
    ignore = shutil.ignore_patterns("__pycache__", ".pytest_cache", "*.egg-info")
    for name in COPIED:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, dest / name, ignore=ignore)
        else:
            shutil.copy2(source, dest / name)
    for name in LINKED:
        (dest / name).symlink_to(ROOT / name)


def extend(copy: Path) -> list[Path]:
    """The four extensions, as docs/extending.md says; returns every file touched."""
    touched = []
    for toy, where in NEW_FILES.items():
        shutil.copy2(TOYS / toy, copy / where)
        touched.append(copy / where)
    for where, line in REGISTRATIONS.items():
        with open(copy / where, "a") as f:
            f.write(line)
        touched.append(copy / where)
    settings = (copy / FIELD_FILE).read_text()
    assert settings.count(FIELD_ANCHOR) == 1
    (copy / FIELD_FILE).write_text(settings.replace(FIELD_ANCHOR, (TOYS / "toy_field.txt").read_text() + "\n" +
                                                    FIELD_ANCHOR))
    touched.append(copy / FIELD_FILE)
    return touched


@pytest.mark.slow
def test_four_extensions_are_each_a_file_a_registration_line_and_a_test(tmp_path):
    copy = tmp_path / "repo"
    copy.mkdir()
    make_copy(copy)
    touched = extend(copy)
    # one file and its test per extension, one line per registry, one settings class: nothing else
    assert len(touched) == len(NEW_FILES) + len(REGISTRATIONS) + 1
    env = {**os.environ, "PYTHONPATH": str(copy), "PYTHONDONTWRITEBYTECODE": "1"}
    lint = subprocess.run([sys.executable, "-m", "ruff", "check", "."], cwd=copy, env=env, capture_output=True,
                          text=True)
    assert lint.returncode == 0, lint.stdout[-3000:]
    # the copy's package is the one imported (its registries hold the toys)
    probe = subprocess.run([sys.executable, "-c", "import egosearch, egosearch.rl.learner_registry as r; "
                            "print(egosearch.__file__, 'toy_bc' in r.LEARNERS)"], cwd=copy, env=env,
                           capture_output=True, text=True)
    assert probe.stdout.split() == [str(copy / "egosearch" / "__init__.py"), "True"], probe.stderr[-2000:]
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "-m", "not slow",
                          *SUITE_CHECKS], cwd=copy, env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stdout[-6000:]
    assert " failed" not in run.stdout and " passed" in run.stdout
