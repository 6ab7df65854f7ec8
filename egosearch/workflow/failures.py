"""A failed job's own reason on the console, not only in its log.

Every rule sends its command's output to its ``log:``; when the command fails, Snakemake prints the rule, its
(long) command and the log's path, and the reason stays in the log. The Snakefile's ``onerror`` calls
:func:`failed_job_lines` on the run's Snakemake log: one line per failed job, its rule and the last line its own
log holds (the one-line error every ``egosearch`` command ends with), so that the last thing a user reads is why.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from pathlib import Path

_ERROR = re.compile(r"^Error in rule (?P<rule>\w+):\s*$")
_LOG = re.compile(r"^\s+log: (?P<paths>.+?)(?: \(check log file\(s\) for error details\))?\s*$")


def failed_jobs(text: str) -> list[tuple[str, list[str]]]:
    """``(rule, its log paths)`` of every "Error in rule" block of a Snakemake log's ``text``, in order."""
    jobs, lines = [], text.splitlines()
    for i, line in enumerate(lines):
        match = _ERROR.match(line)
        if not match:
            continue
        paths: list[str] = []
        for follow in lines[i + 1:i + 12]:
            if not follow.startswith((" ", "\t")):
                break
            log = _LOG.match(follow)
            if log:
                paths = [p.strip() for p in log.group("paths").split(",") if p.strip()]
                break
        jobs.append((match.group("rule"), paths))
    return jobs


def last_line(path: str | Path, read: Callable[[str | Path], str] = lambda p: Path(p).read_text(errors="replace"),
              ) -> str | None:
    """The last line of a job's log that says something (a progress bar's carriage returns cut off), or None."""
    try:
        text = read(path)
    except OSError:
        return None
    for line in reversed(text.splitlines()):
        line = line.rsplit("\r", 1)[-1].strip()
        if line:
            return line
    return None


def run_log_texts(log_paths: str | Path | Iterable[str | Path] | None,
                  read: Callable[[str | Path], str] = lambda p: Path(p).read_text(errors="replace")) -> list[str]:
    """The texts of a run's Snakemake logs: ``log_paths`` is a path or the list the Snakefile's ``onerror`` gets;
    a log that cannot be read is left out."""
    texts = []
    for path in [log_paths] if isinstance(log_paths, (str, Path)) else list(log_paths or ()):
        try:
            texts.append(read(path))
        except OSError:
            continue
    return texts


def failed_job_lines(log_paths: str | Path | Iterable[str | Path],
                     read: Callable[[str | Path], str] = lambda p: Path(p).read_text(errors="replace")) -> list[str]:
    """One line per failed job of the run whose Snakemake log is ``log_paths`` (the path, or the list the
    Snakefile's ``onerror`` gets): ``rule NAME failed: <its log's last line> (log: PATH)``."""
    out = []
    for text in run_log_texts(log_paths, read):
        for rule, logs in failed_jobs(text):
            said = next(((log, line) for log in logs if (line := last_line(log, read))), None)
            if said is None:
                out.append(f"rule {rule} failed" + (f" (log: {', '.join(logs)}, empty)" if logs else ""))
            else:
                out.append(f"rule {rule} failed: {said[1]} (log: {said[0]})")
    return out
