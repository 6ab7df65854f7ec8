"""A toy observation option (the extension test's, tests/test_extending.py): ``proprio`` gains the episode's
steps / 100. Copied to egosearch/sim/toy_step_clock.py in a temporary copy of the repository."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from egosearch.sim.observation_options import ObservationOption


class ToyStepClock(ObservationOption):
    """The steps taken this episode / 100."""

    extra_dims: ClassVar[dict[str, int]] = {"proprio": 1}

    def values(self, env: Any) -> dict[str, np.ndarray]:
        return {"proprio": np.array([env.steps / 100.0], np.float32)}


@dataclass
class ToyStepClockSettings:
    """The option's config field."""

    toy_step_clock: bool = False
    """Paper: False. Ours (a toy of the extension test): True appends the episode's steps / 100 to
    ``proprio``. This CHANGES THE OBSERVATION; no preset sets it."""
