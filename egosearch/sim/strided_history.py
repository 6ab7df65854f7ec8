"""The ``strided_history`` observation option (:mod:`egosearch.sim.observation_options`): the depth stack's five
frames reach back 64 steps instead of 4. A CHANGE OF OBSERVATION, never the paper's.

The paper's policy sees its last K = 5 depth frames (paper 4.1). Held to 5 steps of memory, the tuned frontier
searcher loses most of what it has over the student, and 20 to 50 steps give it back (``snakemake
memory_window``). This option keeps the encoder's cost (still five frames, the same convs) and spaces the frames
out: the newest, and those 1, 4, 16 and 64 steps before it (:data:`STRIDED_OFFSETS`), after the growing strides
of the issue that asked for it and of multi-scale frame stacks (the "frame skipping" of DQN's history, taken
further back). Before the episode's 64th step the older slots hold its first frame, as the env pads its history
at reset, so the replay rebuilds every stack from the frames it stores (:class:`egosearch.rl.replay.ReplayBuffer`
with ``frame_offsets``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from egosearch.sim.observation_options import ObservationOption

STRIDED_OFFSETS = (64, 16, 4, 1, 0)
"""The frames of the depth stack, as steps back from the newest, oldest first."""


class StridedHistory(ObservationOption):
    """Chooses the depth stack's frames (:data:`STRIDED_OFFSETS`); appends nothing to the vectors."""

    frame_offsets: ClassVar[tuple[int, ...]] = STRIDED_OFFSETS


@dataclass
class StridedHistorySettings:
    """The option's config field (every learner's config has it)."""

    strided_history: bool = False
    """Paper: False (the last K = 5 depth frames, paper 4.1). True: the five frames are the newest and those 1,
    4, 16 and 64 steps before it (``egosearch.sim.strided_history``), a longer memory at the same encoder cost,
    after the memory-window measurement (``snakemake memory_window``: the tuned searcher held to 5 steps falls to
    the student's level, 20 to 50 steps give its level back). An env keyword option, recorded with the run's
    config in its actor file, which ``egosearch evaluate`` reads back. This CHANGES THE OBSERVATION, for the
    actor and at evaluation too; no preset turns it on (``ablations/head_on_strided_history.yaml`` screens it)."""
