"""Table 1 and Figure 6 read against the random searcher and the privileged oracle; Figure 7 says
when every bar is 0."""

from pathlib import Path

import pandas as pd

from egosearch.report.data import FULLBODY_COLUMNS
from egosearch.report.figures import ALL_ZERO_NOTE, figure7, figure7_figure, figure7_frame


def _fullbody(root: Path, spl_of) -> list[Path]:
    """One seed of 4 scenarios per setting; ``spl_of(method, M)`` is every episode's SPL."""
    paths = []
    for method, M in [("one_step_short", 1), ("noisy_search", 1), ("ours", 5), ("ours", 20)]:
        spl = spl_of(method, M)
        rows = [dict(zip(FULLBODY_COLUMNS, (i, method, "humanoid_phase", M, 20, int(spl > 0), 100, 5.0, 4.0, spl,
                                            100 // M, 0, 0.1, 3))) for i in range(4)]
        path = root / f"{method}-M{M}" / "seed0.csv"
        path.parent.mkdir(parents=True)
        pd.DataFrame(rows).to_csv(path, index=False)
        paths.append(path)
    return paths


def _texts(fig) -> list[str]:
    return [t.get_text() for ax in fig.axes for t in ax.texts]


def test_figure7_says_so_when_every_bar_is_zero(tmp_path):
    zero = _fullbody(tmp_path / "zero", lambda method, M: 0.0)
    assert ALL_ZERO_NOTE in _texts(figure7_figure(figure7_frame(zero, n_resamples=50)))
    png, _pdf, _csv = figure7(zero, tmp_path / "fig7", n_resamples=50)
    assert png.stat().st_size > 10_000
    # One bar above 0 is a plot to read, not an empty one.
    some = _fullbody(tmp_path / "some", lambda method, M: 0.5 if M == 20 else 0.0)
    assert ALL_ZERO_NOTE not in _texts(figure7_figure(figure7_frame(some, n_resamples=50)))
