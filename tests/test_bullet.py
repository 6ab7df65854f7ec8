"""pybullet's start-up chatter is silenced; everything else it writes still shows."""

from __future__ import annotations

import ctypes
import os
import subprocess
import sys

import pytest

from egosearch.sim.bullet import connect, pybullet, quiet_native_output

_SCRIPT = """
from egosearch.sim.body import AgentSpec
from egosearch.motion.collision import PenetrationCounter
from egosearch.scene.layouts import get_scene
from egosearch.sim.world import World

worlds = [World(get_scene("studio"), AgentSpec()) for _ in range(2)]
counter = PenetrationCounter(get_scene("studio"), "humanoid")
print("ok")
"""


def test_import_and_connect_say_nothing():
    # A fresh interpreter: pybullet's build-time line comes once per process, at import.
    done = subprocess.run([sys.executable, "-c", _SCRIPT], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "ok\n"
    assert done.stderr == ""


def test_only_the_known_lines_are_dropped(capfd):
    with quiet_native_output():
        os.write(1, b"argv[0]=\nkept on stdout\n")
        os.write(2, b"pybullet build time: Jan 1 2025\nkept on stderr\n")
        # C stdio buffers when stdout is not a terminal: it must be flushed into the catch.
        ctypes.CDLL(None).printf(b"argv[0]=x\nfrom C\n")
    out, err = capfd.readouterr()
    assert out == "kept on stdout\nfrom C\n"
    assert err == "kept on stderr\n"


def test_a_real_pybullet_error_still_shows(capfd):
    client = connect()
    with pytest.raises(pybullet.error):
        with quiet_native_output():
            client.loadURDF("no_such_file.urdf")
    out, err = capfd.readouterr()
    assert "URDF file 'no_such_file.urdf' not found" in out + err
    client.disconnect()


def test_streams_come_back_after_an_exception(capfd):
    with pytest.raises(RuntimeError, match="inside"):
        with quiet_native_output():
            os.write(2, b"said before failing\n")
            raise RuntimeError("inside")
    os.write(1, b"after\n")
    out, err = capfd.readouterr()
    assert (out, err) == ("after\n", "said before failing\n")
