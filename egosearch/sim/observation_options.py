"""The body env's observation options by name: keyword options that change what a policy observes, with no env
id of their own (no new id per combination of options).

An option is one module with two classes and one :func:`register` line below:

- its option class, a subclass of :class:`ObservationOption`: the values it appends to the observation's
  vectors (``extra_dims`` and :meth:`ObservationOption.values`), what it keeps over an episode (``reset``,
  ``moved`` after each step's move, ``snapshot``/``restore`` for the replanner);
- its settings class, a dataclass with ONE bool field named as the option, its docstring naming the source
  and saying that it changes the observation (as every config field's does). Every learner's config has the
  field (:mod:`egosearch.rl.config` composes it with the run settings); a run's config records it in its
  actor file, and ``egosearch evaluate`` builds the actor's env with it (``--env-option`` overrides it).

``SearchEnv(..., name=True)`` turns an option on; ``egosearch.envs.OBSERVATION_OPTIONS`` lists the names.
Options and settings are named ``"module:attribute"`` and imported on first use: this module imports nothing
but the registry helper, so that the config and the workflow can read the names without the simulator."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from egosearch.core.named_registry import Registry, resolve


class ObservationOption:
    """One option's state in one env. A subclass sets ``extra_dims`` and overrides what it uses; the env
    calls :meth:`reset` at each reset, :meth:`moved` after each step's move, and appends :meth:`values` to
    the observation's vectors (in registration order, after the env's own values)."""

    extra_dims: ClassVar[Mapping[str, int]] = {}
    """Values appended to each observation vector it changes (``{"proprio": 2}``)."""
    byte_valued: ClassVar[bool] = False
    """Its ``mask`` values are multiples of 1/255 in [0, 1] (an image), which a replay stores as bytes. Such an
    option's values must come last in ``mask`` (:func:`byte_valued_tail`)."""
    image_shape: ClassVar[tuple[int, int, int] | None] = None
    """(channels, rows, columns) when its ``mask`` values are an image a learner reads with convs (channel-major)."""
    frame_offsets: ClassVar[tuple[int, ...] | None] = None
    """The past frames the ``depth`` stack holds instead of the last K, as steps back from the newest, oldest
    first and ending at 0 (K of them; frames before the episode's first are that first frame, as at reset);
    None: the last K. At most one option turned on may set it (:func:`frame_offsets`)."""

    def reset(self, env: Any) -> None:
        """A new episode begins in ``env`` (a :class:`egosearch.sim.env.SearchEnv`)."""

    def moved(self, env: Any, collided: bool) -> None:
        """``env``'s body has just moved this step; ``collided``: whether the move hit something."""

    def values(self, env: Any) -> Mapping[str, Any]:
        """The values to append, per vector: ``{"proprio": array of extra_dims["proprio"] float32 values}``."""
        return {}

    def snapshot(self) -> Any:
        """What :meth:`restore` needs to continue the episode exactly (the replanner's snapshots)."""
        return None

    def restore(self, state: Any) -> None:
        """Back to a :meth:`snapshot`."""


@dataclass(frozen=True)
class RegisteredOption:
    """One registered option: its ``name`` (the env keyword and the config field), its option class and its
    settings class (each the class or ``"module:Class"``)."""

    name: str
    option: str | Callable[[], ObservationOption]
    settings: str | type

    def option_class(self) -> type[ObservationOption]:
        return resolve(self.option)

    def settings_class(self) -> type:
        return resolve(self.settings)


_REGISTRY: Registry[RegisteredOption] = Registry("observation option")
OPTIONS: dict[str, RegisteredOption] = _REGISTRY.entries
"""Every registered observation option by name, in registration order."""


def register(name: str, option: str | Callable[[], ObservationOption], settings: str | type, *,
             replace: bool = False) -> RegisteredOption:
    """Register an observation option (see the module docstring); a name already taken needs ``replace``."""
    return _REGISTRY.add(name, RegisteredOption(name, option, settings), replace=replace)


def unregister(name: str) -> RegisteredOption:
    """Remove a registered option (a test's own, after it)."""
    return _REGISTRY.remove(name)


def option_names() -> tuple[str, ...]:
    """The registered option names, in registration order."""
    return _REGISTRY.names()


def extra_dims(on: Mapping[str, Any]) -> dict[str, int]:
    """The values the options turned on in ``on`` (name -> truthy) append, summed per vector."""
    out: dict[str, int] = {}
    for name, entry in OPTIONS.items():
        if on.get(name):
            for vector, n in entry.option_class().extra_dims.items():
                out[vector] = out.get(vector, 0) + int(n)
    return out


def frame_offsets(on: Mapping[str, Any], frame_history: int) -> tuple[int, ...]:
    """The depth stack's frames (steps back, oldest first) with the options turned on in ``on``: the one option's
    that sets :attr:`ObservationOption.frame_offsets`, else the last ``frame_history`` (K-1, ..., 0). The env,
    the replay and the demonstrations read it here, so that they rebuild the same stacks."""
    chosen = [(name, entry.option_class().frame_offsets) for name, entry in OPTIONS.items()
              if on.get(name) and entry.option_class().frame_offsets is not None]
    if len(chosen) > 1:
        raise ValueError(f"options {' and '.join(n for n, _ in chosen)} both choose the depth stack's frames; "
                         "allowed: one of them")
    if not chosen:
        return tuple(range(int(frame_history) - 1, -1, -1))
    name, offsets = chosen[0]
    offsets = tuple(int(o) for o in offsets)
    if (len(offsets) != int(frame_history) or offsets[-1] != 0
            or any(a <= b for a, b in zip(offsets, offsets[1:]))):
        raise ValueError(f"option {name}: frame_offsets={offsets}; allowed: {frame_history} steps back, "
                         "decreasing, ending at 0")
    return offsets


def byte_valued_tail(on: Mapping[str, Any]) -> int:
    """How many of ``mask``'s last values are byte-valued (:attr:`ObservationOption.byte_valued`) with the options
    turned on in ``on``: a replay stores those as bytes. ValueError when another option's ``mask`` values would
    follow them."""
    tail, after = 0, []
    for name, entry in OPTIONS.items():
        option = entry.option_class()
        n = int(option.extra_dims.get("mask", 0))
        if not on.get(name) or not n:
            continue
        if option.byte_valued:
            tail += n
        elif tail:
            after.append(name)
    if after:
        raise ValueError(f"option(s) {', '.join(after)} append to mask after byte-valued values; register them "
                         "before the image options")
    return tail


def mask_images(on: Mapping[str, Any]) -> list[tuple[int, tuple[int, int, int]]]:
    """``(values before it in the options' part of mask, image shape)`` of each image option turned on in
    ``on``, in the order its values follow one another at the end of ``mask``."""
    out, before = [], 0
    for name, entry in OPTIONS.items():
        option = entry.option_class()
        n = int(option.extra_dims.get("mask", 0))
        if not on.get(name) or not n:
            continue
        if option.image_shape is not None:
            out.append((before, tuple(option.image_shape)))
        before += n
    return out


def build(on: Mapping[str, Any]) -> list[ObservationOption]:
    """Fresh option states for the options turned on in ``on``, in registration order."""
    return [entry.option_class()() for name, entry in OPTIONS.items() if on.get(name)]


# ---- the options ---------------------------------------------------------------------------------

register("contact_signal", "egosearch.sim.contact_signal:ContactSignal",
         "egosearch.sim.contact_signal:ContactSignalSettings")
register("strided_history", "egosearch.sim.strided_history:StridedHistory",
         "egosearch.sim.strided_history:StridedHistorySettings")
# byte-valued images last: a replay stores the end of mask as bytes (byte_valued_tail)
register("map_image", "egosearch.sim.map_image:MapImage", "egosearch.sim.map_image:MapImageSettings")
