"""Per-episode metric formulas, shared by evaluation and the report layer (pure Python)."""

from __future__ import annotations


def episode_spl(success: bool, shortest_path: float, path_length: float) -> float:
    """One term of SPL (paper 6.4): S * l / max(p, l)."""
    if not success:
        return 0.0
    if shortest_path <= 0.0:
        return 1.0  # the start already satisfied success: any path is optimal
    return shortest_path / max(path_length, shortest_path)


def spl(successes, shortest_paths, path_lengths) -> float:
    """SPL = 1/N sum_i S_i l_i / max(p_i, l_i)."""
    terms = [episode_spl(s, l, p) for s, l, p in zip(successes, shortest_paths, path_lengths, strict=True)]
    if not terms:
        raise ValueError("SPL of no episodes is undefined")
    return sum(terms) / len(terms)
