"""This machine's learner rate: a short real cpu-preset training (``egosearch estimate all`` runs it
when no rate is given), remembered in a cache so that ``snakemake all`` and ``egosearch train`` can say
how long a run takes here without a minute's wait.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import time
from pathlib import Path

from egosearch.core.machine import cpu_model, cpu_seconds_all, cpu_vector_unit, own_cpu_seconds
from egosearch.cost.rates import steps_of_preset
from egosearch.cost.schedule import machine_key
from egosearch.rl.config import BODY_STEPS

CALIBRATION_CACHE = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "egosearch" / "learner_rate.json"
"""This machine's last calibration, so that ``snakemake all`` can print the estimate without a minute's wait."""


def this_machine() -> dict:
    """This machine as records name one: its CPU, vector unit and cores."""
    return {"cpu": cpu_model(), "vector_unit": cpu_vector_unit(), "cores": os.cpu_count()}


def calibrate() -> tuple[float, float | None]:
    """This machine's env steps per CPU-second in a short real cpu-preset training (~a minute),
    remembered in :data:`CALIBRATION_CACHE` for this machine, and the cores other processes kept busy
    meanwhile (as ``egosearch bench learner`` records it; None where the system does not say). The
    training's own lines (its evaluations, its config) are held back: the estimate is the answer."""
    # local: loads torch and the simulator, which an estimate from a given --rate never needs
    from egosearch.rl.bench_learner import cpu_preset_run_steps, training_throughput

    busy0, own0, wall0 = cpu_seconds_all(), own_cpu_seconds(), time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        rate = float(training_throughput("cpu", env_steps=cpu_preset_run_steps())["env_steps_per_core_s"])
    wall, busy1, own = time.perf_counter() - wall0, cpu_seconds_all(), own_cpu_seconds() - own0
    other = (round(max(0.0, busy1 - busy0 - own) / wall, 2)
             if busy0 is not None and busy1 is not None and wall > 0 else None)
    try:
        CALIBRATION_CACHE.parent.mkdir(parents=True, exist_ok=True)
        CALIBRATION_CACHE.write_text(json.dumps({"machine": machine_key(this_machine()), "rate": rate,
                                                 "steps": steps_of_preset("cpu"), "other_load_cores": other}))
    except OSError:
        pass  # a read-only home: the next estimate calibrates again
    return rate, other


BUSY_CORES = 0.25
"""Other processes' CPU use during a calibration (cores) above which an estimate says it was measured on
a busy machine: the calibration counts this process's CPU time, but shared caches and memory slow it."""


def cached_calibration() -> dict | None:
    """This machine's last calibration as stored (its ``rate`` and the ``other_load_cores`` meanwhile);
    None when it has none, it was another machine's, or it timed another kind of env step than the cpu
    preset's today."""
    try:
        cached = json.loads(CALIBRATION_CACHE.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(cached, dict):
        return None
    here = machine_key(this_machine())
    same = cached.get("machine") == here and cached.get("steps", BODY_STEPS) == steps_of_preset("cpu")
    return cached if same and cached.get("rate") else None


def cached_rate() -> float | None:
    """This machine's last calibration's rate (None as :func:`cached_calibration`)."""
    cached = cached_calibration()
    return float(cached["rate"]) if cached else None


def cached_busy_line() -> str | None:
    """One line where this machine's last calibration (which every checkout on it shares) was made while
    other processes kept more than :data:`BUSY_CORES` cores busy; None otherwise."""
    cached = cached_calibration()
    other = cached.get("other_load_cores") if cached else None
    if not isinstance(other, (int, float)) or other <= BUSY_CORES:
        return None
    return (f"this machine's last calibration was made while it was busy: other processes used {other:.1f} cores "
            "meanwhile, so its rate may be low and the estimate long (`egosearch estimate all` calibrates again: "
            "run it when the machine is idle)")
