"""What machine a run used: the CPU's name and vector unit, and the GPU's where one was used (stdlib only, so both
the learner and the report layer can record it without importing each other)."""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def cpu_vector_unit(cpuinfo: Path = Path("/proc/cpuinfo")) -> str | None:
    """The widest x86 vector unit the CPU offers ("AVX-512", "AVX2", "AVX"), from /proc/cpuinfo's
    flags; None where they cannot be read. Two CPUs of one model name can differ here (an "AMD
    EPYC" with AVX-512 ran the cpu preset's training about three times as fast as one without),
    so speed records carry it beside the name."""
    try:
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("flags"):
                flags = set(line.split(":", 1)[1].split())
                for flag, name in (("avx512f", "AVX-512"), ("avx2", "AVX2"), ("avx", "AVX")):
                    if flag in flags:
                        return name
                return "no AVX"
    except OSError:
        pass
    return None


def gpu_model() -> str | None:
    """The CUDA device's name where this process uses torch and CUDA is present, else None (torch is
    not imported for the question: a process that never imported it used no GPU)."""
    torch = sys.modules.get("torch")
    if torch is None or not torch.cuda.is_available():
        return None
    return torch.cuda.get_device_name()


def cpu_seconds_all() -> float | None:
    """CPU time (s) every process of the machine has used since boot (/proc/stat), None off Linux."""
    try:
        with open("/proc/stat") as f:
            fields = f.readline().split()[1:]
        return (int(fields[0]) + int(fields[1]) + int(fields[2])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def own_cpu_seconds() -> float:
    """CPU time (s) of this process and of its children that have finished: a benchmark's own share of
    :func:`cpu_seconds_all` (the learner benchmark times its AVX2-limited rows in a child)."""
    t = os.times()
    return time.process_time() + t.children_user + t.children_system


def _git(*args: str) -> str | None:
    try:
        return subprocess.run(["git", *args], capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def gpu_fields(gpu: str | None) -> dict:
    """The GPU part of a machine record: nothing on a machine without one (records stay as they were)."""
    if gpu is None:
        return {}
    import torch

    return {"gpu": gpu, "torch": str(torch.__version__), "cuda": torch.version.cuda,
            "gpu_memory_gib": round(torch.cuda.get_device_properties(0).total_memory / 2**30, 1)}


def measured_on() -> dict:
    """When, at which commit and on what a measurement was made: the date, the commit (and whether the
    tree had local changes) and the machine (CPU, vector unit, cores; the GPU where there is one)."""
    status = _git("status", "--porcelain", "--untracked-files=no")
    return {
        "date_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        # a copy of the tree (a device, a cluster node) is told its commit: its .git, if any, may be stale
        "commit": os.environ.get("EGOSEARCH_COMMIT") or _git("rev-parse", "HEAD") or "unknown",
        "commit_dirty": bool(status) if status is not None else None,
        "machine": {"cpu": cpu_model(), "vector_unit": cpu_vector_unit(), "cores": os.cpu_count(),
                    **gpu_fields(gpu_model())},
    }


MACHINE_PLACEHOLDER = "{machine}"
"""In a record's ``--out`` path: this machine's folder name (:func:`machine_folder_name`), so that each
machine's benchmark and estimate land in a folder of their own (``results/cpu/bench/hosts/{machine}/``)."""


def machine_folder_name(machine: dict) -> str:
    """A machine as a folder name: ``Intel(R) Xeon(R) Processor / AVX-512 / 2 cores`` ->
    ``intel-xeon-processor-avx-512-2-cores`` (and its GPU's name, where it has one)."""
    words = (f"{machine.get('cpu') or 'unknown'} {machine.get('vector_unit') or ''} "
             f"{machine.get('cores') or '?'} cores {machine.get('gpu') or ''}")
    words = words.replace("(R)", "").replace("(TM)", "").lower()
    return "-".join("".join(c if c.isalnum() else " " for c in words).split())


def with_machine(path: str | None) -> str | None:
    """``path`` with :data:`MACHINE_PLACEHOLDER` replaced by this machine's folder name (its GPU's name
    too where torch sees one: a record made there times the GPU's learner)."""
    if not path or MACHINE_PLACEHOLDER not in path:
        return path
    import torch  # the records that take the placeholder time torch anyway

    gpu = torch.cuda.get_device_name() if torch.cuda.is_available() else None
    here = {"cpu": cpu_model(), "vector_unit": cpu_vector_unit(), "cores": os.cpu_count(), "gpu": gpu}
    return path.replace(MACHINE_PLACEHOLDER, machine_folder_name(here))
