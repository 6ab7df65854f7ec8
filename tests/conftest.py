import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

# Headless pictures: EGL for pyrender, Agg for matplotlib. Set before anything imports them.
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
os.environ.setdefault("MPLBACKEND", "Agg")

PORTABLE_KERNELS = {"ATEN_CPU_CAPABILITY": "default", "MKL_CBWR": "COMPATIBLE", "DNNL_MAX_CPU_ISA": "SSE41",
                    "ONEDNN_MAX_CPU_ISA": "SSE41"}
"""The CPU kernels that give the same floats on every x86-64 host: torch's scalar kernels, MKL's
conditional-numerical-reproducibility mode, oneDNN's SSE4.1 code. By default each picks code by the
host's instruction set (AVX2, AVX-512), which sums in another order: the pinned hashes of
test_learner_updates_pinned, made on an AVX-512 host, moved on an AVX2 host with the same code, and a
grouped convolution's gradient parted from four separate ones by 100 times its AVX-512 rounding. They
are read once, when a library loads, hence a fresh process."""

INSIDE_PORTABLE = "EGOSEARCH_TEST_PORTABLE_KERNELS"
"""Set in that fresh process, where the test runs itself."""

ROOT = Path(__file__).resolve().parent.parent


def pytest_configure(config):
    config.addinivalue_line("markers", "portable_kernels: runs in a fresh process on PORTABLE_KERNELS (conftest)")


@pytest.hookimpl(tryfirst=True)
def pytest_pyfunc_call(pyfuncitem):
    """A test marked ``portable_kernels`` runs again in a fresh Python with :data:`PORTABLE_KERNELS`
    set, and passes or fails as it does there."""
    if pyfuncitem.get_closest_marker("portable_kernels") is None or os.environ.get(INSIDE_PORTABLE) == "1":
        return None
    env = {**os.environ, **PORTABLE_KERNELS, INSIDE_PORTABLE: "1"}
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-o", "addopts=",
                          pyfuncitem.nodeid], cwd=ROOT, env=env, capture_output=True, text=True)
    if run.returncode != 0 or re.search(r"\b1 passed\b", run.stdout) is None:  # a skip there is no pass here
        pytest.fail(f"on portable kernels:\n{run.stdout[-6000:]}{run.stderr[-2000:]}", pytrace=False)
    return True
