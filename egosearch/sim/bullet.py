"""pybullet without its start-up chatter: import it and connect through here.

pybullet writes ``pybullet build time: ...`` to stderr when it is imported and ``argv[0]=`` to
stdout on every connect (``bullet_client`` always passes an options string). Both come from C,
so they are caught at the file-descriptor level, and only around those two calls. Anything
else written meanwhile is handed back to the stream it was written to: a real error from
pybullet still shows.
"""

from __future__ import annotations

import contextlib
import ctypes
import importlib
import os
import sys
import tempfile

#: Lines pybullet prints on import and connect that carry no information for a user.
NOISE_PREFIXES = ("pybullet build time:", "argv[0]=")


def _flush_c_stdio() -> None:
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # no C library to reach: nothing of ours is buffered there
        pass


@contextlib.contextmanager
def quiet_native_output(noise: tuple[str, ...] = NOISE_PREFIXES):
    """Hold what is written to fds 1 and 2 during the block, then pass on every line that
    does not start with one of ``noise``, each to the stream it came from."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    try:
        saved = {fd: os.dup(fd) for fd in (1, 2)}
    except OSError:  # a closed stdout or stderr: nothing to keep quiet
        yield
        return
    sinks = {fd: tempfile.TemporaryFile() for fd in saved}
    try:
        for fd, sink in sinks.items():
            os.dup2(sink.fileno(), fd)
        yield
    finally:
        _flush_c_stdio()
        for fd, copy in saved.items():
            os.dup2(copy, fd)
            os.close(copy)
        for fd, sink in sinks.items():
            sink.seek(0)
            kept = [line for line in sink.read().splitlines(keepends=True)
                    if not line.decode(errors="replace").lstrip().startswith(noise)]
            sink.close()
            if kept:
                os.write(fd, b"".join(kept))


with quiet_native_output():
    pybullet = importlib.import_module("pybullet")
    bullet_client = importlib.import_module("pybullet_utils.bullet_client")


def connect():
    """A new headless pybullet client (``BulletClient``), without the connect chatter."""
    with quiet_native_output():
        return bullet_client.BulletClient(connection_mode=pybullet.DIRECT)
