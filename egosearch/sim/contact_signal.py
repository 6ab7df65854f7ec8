"""The ``contact_signal`` observation option (:mod:`egosearch.sim.observation_options`): habitat-lab's
``collisions`` measure given to the policy. A CHANGE OF OBSERVATION, never the paper's.

``proprio`` gains :data:`CONTACT_SIGNAL_DIM` values: whether this step's move collided (a bump bit) and the
collisions of the last :data:`CONTACT_WINDOW` steps / :data:`CONTACT_WINDOW`. The paper's body feels
nothing: a low sofa below the view is invisible to it, and the stored students fail pushing into such
furniture."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from egosearch.sim.observation_options import ObservationOption

CONTACT_WINDOW = 5
"""Steps over which the option counts the body's collisions."""
CONTACT_SIGNAL_DIM = 2
"""Values the option appends to ``proprio``: whether this step's move collided, and the collisions of the last
:data:`CONTACT_WINDOW` steps / :data:`CONTACT_WINDOW`."""


class ContactSignal(ObservationOption):
    """The bump bit and the recent collision count (module docstring)."""

    extra_dims: ClassVar[dict[str, int]] = {"proprio": CONTACT_SIGNAL_DIM}

    def __init__(self) -> None:
        self.recent: deque[int] = deque([0] * CONTACT_WINDOW, maxlen=CONTACT_WINDOW)

    def reset(self, env: Any) -> None:
        self.recent.extend([0] * CONTACT_WINDOW)

    def moved(self, env: Any, collided: bool) -> None:
        self.recent.append(int(collided))

    def values(self, env: Any) -> dict[str, np.ndarray]:
        return {"proprio": np.array([self.recent[-1], sum(self.recent) / CONTACT_WINDOW], np.float32)}

    def snapshot(self) -> tuple[int, ...]:
        return tuple(self.recent)

    def restore(self, state: tuple[int, ...]) -> None:
        self.recent.extend(state)


@dataclass
class ContactSignalSettings:
    """The option's config field (every learner's config has it)."""

    contact_signal: bool = False
    """Paper: False (the body feels nothing: its observation is depth, the target mask and the head's
    pose). True: habitat-lab's ``collisions`` measure given to the policy, after the stuck-student read
    (``docs/results.md``, "What head_on is stuck against": a fifth of the stuck runs press into furniture
    whose top is below the view): the env's ``contact_signal`` option, whose ``proprio`` gains a bump bit
    and the collisions of the last 5 steps / 5 (``egosearch.sim.contact_signal``). It keeps the variant's env
    id (an env keyword option, recorded with the run's config in its actor file, which ``egosearch evaluate``
    reads back). This CHANGES THE OBSERVATION, for the actor and at evaluation too: the ``cpu`` preset's
    since the stuck-student redo (``ablations/head_on_contact_signal.yaml`` screened it alone on three
    seeds)."""
