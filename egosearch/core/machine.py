"""What machine a run used: the CPU's name and vector unit, and the GPU's where one was used (stdlib only, so both
the learner and the report layer can record it without importing each other)."""

from __future__ import annotations

import os
import platform
import sys
import time
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
    EPYC" with AVX-512 ran the cpu profile's training about three times as fast as one without),
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
