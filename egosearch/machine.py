"""What machine a run used: the CPU's name, and the GPU's where one was used (stdlib only, so both
the learner and the report layer can record it without importing each other)."""

from __future__ import annotations

import platform
import sys
from pathlib import Path


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def gpu_model() -> str | None:
    """The CUDA device's name where this process uses torch and CUDA is present, else None (torch is
    not imported for the question: a process that never imported it used no GPU)."""
    torch = sys.modules.get("torch")
    if torch is None or not torch.cuda.is_available():
        return None
    return torch.cuda.get_device_name()
