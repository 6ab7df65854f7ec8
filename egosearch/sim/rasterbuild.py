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


def installed_library() -> Path | None:
    """The library ``pip install`` built beside this file (``setup.py``), if it did."""
    import importlib.machinery

    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        path = SOURCE.with_name(f"{LIBRARY}{suffix}")
        if path.is_file():
            return path
    return None


def find_compiler() -> str | None:
    """The C compiler a first use would compile the rasteriser with: ``$CC``, cc, gcc or clang."""
    import shutil

    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


NOT_BUILT = ("note: egosearch's C depth rasteriser was not built at install and no C compiler is on PATH: the "
             "sensor uses Embree (same images, slower); install a C compiler and `pip install -e .` again to build it")
"""What the first ``egosearch`` command says once on such an install: pip shows a build's own warning
only under ``pip -v``, so the install's warning goes unseen."""


def notice_once(marker: Path) -> str | None:
    """:data:`NOT_BUILT` the first time it applies on this machine (``marker`` remembers it was said),
    else None."""
    if installed_library() is not None or find_compiler() is not None or marker.exists():
        return None
    try:
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.write_text(NOT_BUILT + "\n")
    except OSError:
        pass  # an unwritable home: the note comes again next time, which is better than never
    return NOT_BUILT
