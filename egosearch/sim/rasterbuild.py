"""How the depth sensor's C rasteriser (``raster.c``) is compiled, in one place for both builds:
``setup.py`` builds it at ``pip install`` (beside this file, as ``_raster<extension suffix>``), and
:mod:`egosearch.sim.sensor` compiles it on first use into a cache when the install could not.

Standard library only: ``setup.py`` loads this file by its path, before egosearch's dependencies
(numpy...) are installed.

Every build records what it was built from and for, as the string its ``egosearch_raster_build()``
returns (``"<source key> <target>"``), and the loader uses a library only when :func:`usable_here`:
an installed library left from an older ``raster.c`` (an editable install whose source changed
since) may not match the calls of :mod:`egosearch.sim.sensor`, and one tuned with ``-march=native`` may
stop with an illegal instruction on another CPU (an install shared by cluster nodes of another kind).
"""

from __future__ import annotations

import hashlib
import os
import platform
from pathlib import Path

SOURCE = Path(__file__).with_name("raster.c")
LIBRARY = "_raster"
"""The installed library's name in the package: ``egosearch/sim/_raster<EXTENSION_SUFFIX>``."""
PORTABLE = "portable"
BASE_FLAGS = ("-O3", "-fno-math-errno")
"""Beside the compiler's own for a shared library (-fPIC -shared)."""
NATIVE_BUILD_ENV = "EGOSEARCH_NATIVE_BUILD"
"""``0`` at install: build for any CPU of the architecture (an install shared by unlike machines)."""


def cpu_signature() -> str:
    """What code tuned for this CPU may assume about it: the architecture, model and feature flags."""
    text = platform.machine() + platform.processor()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith(("flags", "Features", "model name")):
                    text += line
                    if line.startswith(("flags", "Features")):
                        break
    except OSError:
        pass
    return text


def cpu_key() -> str:
    return hashlib.sha1(cpu_signature().encode()).hexdigest()[:16]


def source_key() -> str:
    return hashlib.sha1(SOURCE.read_bytes()).hexdigest()[:16]


def flag_sets(native: bool = True) -> list[list[str]]:
    """Compiler flags to try in turn: tuned for this CPU (when ``native``), then portable. Each
    defines the build string the library reports (see the module docstring)."""
    def build(target: str) -> str:
        return f'-DEGOSEARCH_RASTER_BUILD="{source_key()} {target}"'

    portable = [*BASE_FLAGS, build(PORTABLE)]
    return [[*BASE_FLAGS, "-march=native", build(cpu_key())], portable] if native else [portable]


def usable_here(build: str) -> str | None:
    """None when a library reporting ``build`` may be used here; else why not, in words."""
    source, _, target = build.partition(" ")
    if source != source_key():
        return "it was built from another raster.c (reinstall: pip install -e .)"
    if target not in (PORTABLE, cpu_key()):
        return "it was tuned for another CPU (-march=native)"
    return None


def native_wanted() -> bool:
    return os.environ.get(NATIVE_BUILD_ENV, "1").strip() != "0"
