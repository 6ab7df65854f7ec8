"""The depth sensor's C rasteriser, built at ``pip install`` as an optional extension (the project's
metadata is in pyproject.toml).

``raster.c`` is a plain shared library that :mod:`egosearch.sim.sensor` loads with ctypes (no Python
headers involved), so it is built as ``egosearch/sim/_raster<extension suffix>``. Without a working C
compiler the install goes on without it, as PyYAML's and msgpack's C speed-ups do: the sensor then
compiles it on first use when a compiler appears, else uses Embree (slower, same images).
"""

import importlib.util
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.errors import CCompilerError, ExecError, PlatformError


def _rasterbuild():
    # by path: the package's __init__ and dependencies are not importable while it is being built
    path = Path(__file__).resolve().parent / "egosearch" / "sim" / "rasterbuild.py"
    spec = importlib.util.spec_from_file_location("_egosearch_rasterbuild", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


rasterbuild = _rasterbuild()
BUILD_ERRORS = (CCompilerError, ExecError, PlatformError, OSError)


class OptionalBuildExt(build_ext):
    """Tries the flags of :func:`egosearch.sim.rasterbuild.flag_sets` in turn; when none builds, warns and
    leaves the extension out instead of failing the install."""

    def run(self):
        try:
            super().run()
        except BUILD_ERRORS as err:  # no compiler at all (e.g. none configured on Windows)
            self._warn(err)

    def build_extension(self, ext):
        errors = []
        for flags in rasterbuild.flag_sets(native=rasterbuild.native_wanted()):
            ext.extra_compile_args = flags
            try:
                super().build_extension(ext)
                return
            except BUILD_ERRORS as err:
                errors.append(err)
        self._warn(errors[-1])

    @staticmethod
    def _warn(err):
        print(f"WARNING: egosearch's C depth rasteriser was not built ({err}); egosearch installs without it "
              "and its sensor compiles it on first use if a C compiler is found then, else uses Embree "
              "(slower, same images)", file=sys.stderr)


setup(
    ext_modules=[Extension(f"egosearch.sim.{rasterbuild.LIBRARY}", sources=["egosearch/sim/raster.c"],
                           libraries=[] if sys.platform == "win32" else ["m"], optional=True)],
    cmdclass={"build_ext": OptionalBuildExt},
)
