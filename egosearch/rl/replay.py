"""A frame-deduplicating replay buffer for K-frame depth stacks.

The env's observation holds the last K depth frames (oldest first); consecutive observations
share K-1 of them. Storing obs and next_obs stacks would cost 2K frames per transition; this
buffer stores each depth frame ONCE (uint8, ``image_size`` x ``image_size``) in a ring of frames
and rebuilds both stacks by index at sample time.

Layout
------
- A frame ring of ``n_frames`` slots. An episode of T transitions writes T + 1 frames in a row:
  its first observation's newest frame f_0 (at the episode's first ``add``) and then the newest
  frame f_{t+1} of every next observation.
- A transition ring of ``capacity`` slots holding, per transition, the absolute number of the
  frame f_t (newest frame of obs_t), the step t within its episode, the action, the reward, the
  terminated/truncated flags and the (small) mask / proprio vectors of obs and next_obs (and,
  with ``state_dim`` > 0, the env's privileged ``state`` vectors, for a privileged critic).
- The stack of obs_t is frames [f_{max(t-K+1+j, 0)} for j = 0..K-1] (oldest first), and that of
  next_obs_t is the same shifted by one, so one gather of K + 1 frames yields both
  (obs = [:, :K], next_obs = [:, 1:]).

Padding at episode starts: frames before the episode's first frame are the FIRST FRAME OF THE
EPISODE repeated, exactly as the env pads its history at reset (it repeats the first frame K
times). Frames never leak across episode boundaries.

Every frame costs 1 + 1/T slots (T = episode length), so the frame ring is slightly larger than
the transition ring: ``n_frames = capacity + capacity // 8 + K + 1`` keeps all ``capacity``
transitions sampleable as long as episodes average >= 8 steps; with shorter episodes the oldest
transitions whose frames were overwritten are dropped from sampling (never returned corrupted).

At 100k transitions (Table 2) this is ~1.14 GB (:func:`replay_gb`), vs. ~10 GB for naively
stored obs + next_obs stacks.

Strided stacks: with ``frame_offsets`` (steps back, oldest first, ending at 0; the ``strided_history`` option's
64, 16, 4, 1, 0) the stack of obs_t is frames [f_{max(t - offset_j, 0)}] and that of next_obs_t the same at t + 1,
two gathers instead of one window; the frame ring grows by the largest offset, so that every stored transition
still finds its oldest frame.

Checkpoints: :meth:`ReplayBuffer.save` / :meth:`load` write / read an ``.npz`` (hundreds of MB
to GB: keep them out of version control; name them ``*.replay.npz``, which is git-ignored).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch

_FORMAT = "egosearch-replay-v1"


def frame_slots(capacity: int, frame_history: int, reach: int | None = None) -> int:
    """Frame-ring size for a transition capacity (see the module docstring); ``reach``: the oldest frame a stack
    holds, in steps back (default K - 1)."""
    reach = frame_history - 1 if reach is None else int(reach)
    return capacity + capacity // 8 + reach + 2


def replay_gb(capacity: int = 100_000, image_size: int = 100, frame_history: int = 5,
              mask_dim: int = 30, proprio_dim: int = 4, action_dim: int = 5, state_dim: int = 0) -> float:
    """Exact memory (GB = 1e9 bytes) of the arrays of a :class:`ReplayBuffer`."""
    frames = frame_slots(capacity, frame_history) * image_size * image_size  # uint8
    per_transition = (8 + 4  # frame number (int64), step in episode (int32)
                      + 4 * action_dim + 4  # action, reward (float32)
                      + 2  # terminated, truncated (bool)
                      + 4 * 2 * (mask_dim + proprio_dim + state_dim))  # of obs and next_obs
    return (frames + capacity * per_transition) / 1e9


class ReplayBuffer:
    """FIFO replay of (obs, action, reward, next_obs, terminated, truncated).

    ``add`` takes the env's dict observations (``depth`` (K, H, W) uint8 oldest first, ``mask``,
    ``proprio``) and keeps only the newest depth frame of each. ``sample`` returns torch tensors
    on ``device``: ``obs_depth`` / ``next_obs_depth`` (B, K, H, W) uint8 (two views of one
    (B, K+1, H, W) gather), ``mask``, ``proprio``, ``next_mask``, ``next_proprio``, ``action``,
    ``reward`` (B, 1), ``not_done`` (B, 1) = 1 - terminated (time-limit truncation still
    bootstraps, as in CURL) and ``index`` (absolute transition numbers); with ``state_dim`` > 0
    also ``state`` / ``next_state`` (the observations' privileged ``state`` entries).
    """

    def __init__(self, capacity: int, image_size: int = 100, frame_history: int = 5,
                 mask_dim: int = 30, proprio_dim: int = 4, action_dim: int = 5,
                 device: str | torch.device = "cpu", seed: int | None = None, state_dim: int = 0,
                 frame_offsets: tuple[int, ...] | None = None, mask_bytes: int = 0):
        if capacity < 1:
            raise ValueError(f"ReplayBuffer capacity={capacity} is out of range; allowed: >= 1")
        self.capacity = int(capacity)
        self.image_size = int(image_size)
        self.k = int(frame_history)
        last_k = tuple(range(self.k - 1, -1, -1))
        offsets = last_k if frame_offsets is None else tuple(int(o) for o in frame_offsets)
        if len(offsets) != self.k or offsets[-1] != 0 or any(a <= b for a, b in zip(offsets, offsets[1:])):
            raise ValueError(f"frame_offsets={offsets}; allowed: {self.k} steps back, decreasing, ending at 0")
        self.offsets = offsets
        self.strided = offsets != last_k
        """Whether the stacks hold other frames than the last K (two gathers at sample time)."""
        self.mask_dim, self.proprio_dim, self.action_dim = int(mask_dim), int(proprio_dim), int(action_dim)
        self.device = torch.device(device)
        self.n_frames = frame_slots(self.capacity, self.k, self.offsets[0])
        self.frames = np.zeros((self.n_frames, self.image_size, self.image_size), np.uint8)
        c = self.capacity
        self.frame_no = np.zeros(c, np.int64)  # absolute frame number of f_t
        self.t_in_ep = np.zeros(c, np.int32)
        self.action = np.zeros((c, self.action_dim), np.float32)
        self.reward = np.zeros(c, np.float32)
        self.terminated = np.zeros(c, bool)
        self.truncated = np.zeros(c, bool)
        if not 0 <= int(mask_bytes) <= self.mask_dim:
            raise ValueError(f"mask_bytes={mask_bytes}; allowed: 0..mask_dim={self.mask_dim}")
        self.mask_bytes = int(mask_bytes)
        """The last this many mask values are multiples of 1/255 (an image option's), stored as bytes."""
        floats = self.mask_dim - self.mask_bytes
        self.mask = np.zeros((c, floats), np.float32)
        self.proprio = np.zeros((c, self.proprio_dim), np.float32)
        self.next_mask = np.zeros((c, floats), np.float32)
        self.mask_u8 = np.zeros((c, self.mask_bytes), np.uint8)
        self.next_mask_u8 = np.zeros((c, self.mask_bytes), np.uint8)
        self.next_proprio = np.zeros((c, self.proprio_dim), np.float32)
        self.state_dim = int(state_dim)
        self.state = np.zeros((c, self.state_dim), np.float32)
        self.next_state = np.zeros((c, self.state_dim), np.float32)
        self.n_added = 0  # transitions ever added
        self.frames_written = 0  # frames ever written
        self.episode_start = 0  # absolute frame number of the current episode's f_0
        self.t = 0  # step of the next transition within the current episode
        self.in_episode = False
        self.rng = np.random.default_rng(seed)

    # ---- writing -----------------------------------------------------------------------
    def __len__(self) -> int:
        """Transitions that can be sampled."""
        return self.n_added - self._first_valid()

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in self._arrays().values())

    def new_episode(self) -> None:
        """Force the next :meth:`add` to start a new episode (e.g. after resuming a run, when
        the env was reset although the last stored transition did not end its episode)."""
        self.in_episode = False

    def begin_mid_episode(self, obs: dict) -> None:
        """Start a stored episode at ``obs``, a state inside an env episode: its whole depth stack is
        written as the frames before its transition, so that the stored state rebuilds exactly (a
        DAgger round that keeps only some of the student's states). The next :meth:`add` takes ``obs``."""
        if self.strided:
            raise ValueError("a replay of strided stacks cannot start mid-episode: the frames before the stack's "
                             "slots are not in the observation")
        depth = obs["depth"]
        if depth.shape != (self.k, self.image_size, self.image_size):
            raise ValueError(f"depth must have shape {(self.k, self.image_size, self.image_size)}, got {depth.shape}")
        self.episode_start = self._write_frame(depth[0])
        for frame in depth[1:]:
            self._write_frame(frame)
        self.t = self.k - 1  # frame j of the stack is f_{t-(k-1)+j}: the frames just written
        self.in_episode = True

    def _write_frame(self, frame: np.ndarray) -> int:
        no = self.frames_written
        self.frames[no % self.n_frames] = frame
        self.frames_written += 1
        return no

    def add(self, obs: dict, action, reward: float, next_obs: dict, terminated: bool,
            truncated: bool) -> None:
        depth, next_depth = obs["depth"], next_obs["depth"]
        expected = (self.k, self.image_size, self.image_size)
        if depth.shape != expected or next_depth.shape != expected:
            raise ValueError(f"depth must have shape {expected}, got {depth.shape} / {next_depth.shape}")
        if not self.in_episode:
            self.episode_start = self._write_frame(depth[-1])
            self.t = 0
            self.in_episode = True
        elif not np.array_equal(self.frames[(self.frames_written - 1) % self.n_frames], depth[-1]):
            raise ValueError("obs does not continue the previous transition's next_obs; the last "
                             "transition did not end its episode (call new_episode() after a reset)")
        i = self.n_added % self.capacity
        self.frame_no[i] = self.frames_written - 1
        self.t_in_ep[i] = self.t
        self.action[i] = np.asarray(action, np.float32).reshape(self.action_dim)
        self.reward[i] = float(reward)
        self.terminated[i] = bool(terminated)
        self.truncated[i] = bool(truncated)
        self._store_mask(self.mask, self.mask_u8, i, obs["mask"])
        self.proprio[i] = obs["proprio"]
        self._store_mask(self.next_mask, self.next_mask_u8, i, next_obs["mask"])
        self.next_proprio[i] = next_obs["proprio"]
        if self.state_dim:
            self.state[i] = obs["state"]
            self.next_state[i] = next_obs["state"]
        self._write_frame(next_depth[-1])
        self.n_added += 1
        self.t += 1
        if terminated or truncated:
            self.in_episode = False

    def _store_mask(self, floats: np.ndarray, octets: np.ndarray, i: int, mask) -> None:
        mask = np.asarray(mask, np.float32)
        if not self.mask_bytes:
            floats[i] = mask
            return
        floats[i] = mask[:-self.mask_bytes]
        octets[i] = np.round(mask[-self.mask_bytes:] * 255.0).astype(np.uint8)

    def masks(self, i: np.ndarray, nxt: bool = False) -> np.ndarray:
        """The (B, mask_dim) float32 mask vectors of obs (``nxt``: next_obs) at ring slots ``i``, as the env gave
        them (byte-valued values back to multiples of 1/255)."""
        floats, octets = (self.next_mask, self.next_mask_u8) if nxt else (self.mask, self.mask_u8)
        if not self.mask_bytes:
            return floats[i]
        return np.concatenate([floats[i], octets[i].astype(np.float32) / np.float32(255.0)], axis=-1)

    # ---- reading -----------------------------------------------------------------------
    def _oldest_frame_needed(self, n: np.ndarray | int) -> np.ndarray:
        i = np.asarray(n) % self.capacity
        f, t = self.frame_no[i], self.t_in_ep[i]
        return f - np.minimum(t, self.offsets[0])

    def _first_valid(self) -> int:
        """Absolute number of the oldest transition whose frames are all still stored."""
        lo = max(0, self.n_added - self.capacity)
        if self.n_added == 0:
            return 0
        lowest_frame = self.frames_written - self.n_frames  # frames below this are overwritten
        if lowest_frame <= 0 or self._oldest_frame_needed(lo) >= lowest_frame:
            return lo
        hi = self.n_added - 1  # the newest transition is always valid
        while lo < hi:  # oldest-frame-needed is non-decreasing in n: binary search
            mid = (lo + hi) // 2
            if self._oldest_frame_needed(mid) >= lowest_frame:
                hi = mid
            else:
                lo = mid + 1
        return lo

    def frame_numbers(self, n: np.ndarray) -> np.ndarray:
        """(B, K+1) absolute frame numbers: obs stack = [:, :K], next_obs stack = [:, 1:]."""
        i = np.asarray(n) % self.capacity
        f, t = self.frame_no[i], self.t_in_ep[i].astype(np.int64)
        back = np.arange(self.k - 1, -2, -1)  # K-1, ..., 0, -1
        # frame j of the (K+1)-window is f_{max(t - back_j, 0)} of this episode
        return f[:, None] - np.minimum(back[None, :], t[:, None])

    def strided_frame_numbers(self, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(B, K) absolute frame numbers of the obs and next_obs stacks of strided stacks."""
        i = np.asarray(n) % self.capacity
        f, t = self.frame_no[i], self.t_in_ep[i].astype(np.int64)
        back = np.asarray(self.offsets, np.int64)[None, :]
        return f[:, None] - np.minimum(back, t[:, None]), f[:, None] + 1 - np.minimum(back, t[:, None] + 1)

    def stacks(self, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rebuilt (obs, next_obs) depth stacks (B, K, H, W) uint8 for absolute indices ``n``."""
        if self.strided:
            obs, nxt = self.strided_frame_numbers(n)
            return self.frames[obs % self.n_frames], self.frames[nxt % self.n_frames]
        window = self.frames[self.frame_numbers(n) % self.n_frames]
        return window[:, :-1], window[:, 1:]

    def sample_indices(self, batch_size: int) -> np.ndarray:
        lo = self._first_valid()
        if self.n_added - lo < 1:
            raise ValueError("cannot sample from an empty ReplayBuffer")
        return self.rng.integers(lo, self.n_added, size=batch_size)

    def sample(self, batch_size: int, indices: np.ndarray | None = None) -> dict[str, torch.Tensor]:
        n = self.sample_indices(batch_size) if indices is None else np.asarray(indices)
        i = n % self.capacity
        pin = self.device.type == "cuda"
        dev = self.device

        def put(a: np.ndarray) -> torch.Tensor:
            x = torch.from_numpy(np.ascontiguousarray(a))
            return x.pin_memory().to(dev, non_blocking=True) if pin else x.to(dev)

        if self.strided:
            obs_depth, next_obs_depth = (put(stack) for stack in self.stacks(n))
        else:
            window = torch.from_numpy(self.frames[self.frame_numbers(n) % self.n_frames])
            window = window.pin_memory().to(dev, non_blocking=True) if pin else window.to(dev)
            obs_depth, next_obs_depth = window[:, :-1], window[:, 1:]
        batch = {
            "obs_depth": obs_depth,
            "next_obs_depth": next_obs_depth,
            "mask": put(self.masks(i)),
            "proprio": put(self.proprio[i]),
            "next_mask": put(self.masks(i, nxt=True)),
            "next_proprio": put(self.next_proprio[i]),
            "action": put(self.action[i]),
            "reward": put(self.reward[i][:, None]),
            "not_done": put((~self.terminated[i]).astype(np.float32)[:, None]),
            "index": torch.from_numpy(n),
        }
        if self.state_dim:
            batch["state"], batch["next_state"] = put(self.state[i]), put(self.next_state[i])
        return batch

    def latest(self, count: int) -> dict[str, torch.Tensor]:
        """The newest ``count`` transitions, oldest first (an on-policy learner's rollout): as
        :meth:`sample` gives them, plus ``truncated`` (B, 1). ``ValueError`` unless all are stored."""
        first = self.n_added - int(count)
        if count < 1 or first < self._first_valid():
            raise ValueError(f"cannot take the latest {count} transitions: {len(self)} are stored")
        batch = self.sample(count, indices=np.arange(first, self.n_added))
        i = batch["index"].numpy() % self.capacity
        batch["truncated"] = torch.from_numpy(self.truncated[i].astype(np.float32)[:, None]).to(self.device)
        return batch

    # ---- checkpoints ----------------------------------------------------------------------
    _SCALARS = ("capacity", "image_size", "k", "mask_dim", "proprio_dim", "action_dim",
                "n_frames", "n_added", "frames_written", "episode_start", "t", "in_episode")

    def _arrays(self) -> dict[str, np.ndarray]:
        return {name: getattr(self, name) for name in (
            "frames", "frame_no", "t_in_ep", "action", "reward", "terminated", "truncated",
            "mask", "proprio", "next_mask", "next_proprio", "state", "next_state", "mask_u8", "next_mask_u8")}

    def state_dict(self) -> dict:
        """Plain arrays + scalars (only the filled part of the rings)."""
        state = {name: int(getattr(self, name)) for name in self._SCALARS}
        n_tr = min(self.n_added, self.capacity)
        n_fr = min(self.frames_written, self.n_frames)
        for name, arr in self._arrays().items():
            state[name] = arr[:n_fr] if name == "frames" else arr[:n_tr]
        state["rng"] = rng_to_plain(self.rng)
        state["format"] = _FORMAT
        if self.strided:  # only then: states of last-K stacks keep their keys
            state["frame_offsets"] = list(self.offsets)
        return state

    def load_state_dict(self, state: dict) -> None:
        if state.get("format") != _FORMAT:
            raise ValueError(f"not a replay buffer state (format={state.get('format')!r})")
        for name in ("capacity", "image_size", "k", "mask_dim", "proprio_dim", "action_dim"):
            if int(state[name]) != getattr(self, name):
                raise ValueError(f"replay buffer state has {name}={int(state[name])}, "
                                 f"this buffer has {getattr(self, name)}")
        held = tuple(int(o) for o in state.get("frame_offsets", range(self.k - 1, -1, -1)))
        if held != self.offsets:
            raise ValueError(f"replay buffer state holds stacks of frames {held} steps back, this buffer "
                             f"{self.offsets}")
        for name, arr in self._arrays().items():
            if name not in state and arr.shape[1:] == (0,):  # written before states (or byte masks) existed
                continue
            src = np.asarray(state[name])
            if src.shape[1:] != arr.shape[1:] or src.shape[0] > arr.shape[0]:
                raise ValueError(f"replay buffer state array {name} has shape {src.shape}")
            arr[:src.shape[0]] = src
        for name in self._SCALARS:
            setattr(self, name, bool(state[name]) if name == "in_episode" else int(state[name]))
        self.rng.bit_generator.state = rng_from_plain(state["rng"])

    def save(self, path: str | os.PathLike) -> Path:
        """Write an ``.npz`` atomically (temp file in the same folder, fsync, rename)."""
        path = Path(path)
        tmp = path.with_name(f".tmp{os.getpid()}.{path.name}")
        state = self.state_dict()
        arrays = {k: v for k, v in state.items() if isinstance(v, np.ndarray)}
        meta = {k: v for k, v in state.items() if not isinstance(v, np.ndarray)}
        import json

        with open(tmp, "wb") as f:
            np.savez(f, __meta__=np.frombuffer(json.dumps(meta).encode(), np.uint8), **arrays)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        return path

    def load(self, path: str | os.PathLike) -> None:
        import json
        import zipfile

        try:
            with np.load(path, allow_pickle=False) as data:
                meta = json.loads(bytes(data["__meta__"]).decode())
                state = {**meta, **{k: data[k] for k in data.files if k != "__meta__"}}
        except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError) as err:
            raise ValueError(f"cannot read replay buffer {path}: {type(err).__name__}: {err}") from None
        self.load_state_dict(state)


def rng_to_plain(rng: np.random.Generator) -> dict:
    """A numpy generator's state as plain values (a checkpoint stores them)."""
    state = rng.bit_generator.state
    return {"bit_generator": state["bit_generator"],
            "state": {k: str(v) for k, v in state["state"].items()},
            "has_uint32": int(state["has_uint32"]), "uinteger": str(state["uinteger"])}


def rng_from_plain(plain: dict) -> dict:
    """The bit generator state that :func:`rng_to_plain` stored."""
    return {"bit_generator": plain["bit_generator"],
            "state": {k: int(v) for k, v in plain["state"].items()},
            "has_uint32": int(plain["has_uint32"]), "uinteger": int(plain["uinteger"])}


class MultiReplay:
    """One :class:`ReplayBuffer` ring per env of a lockstep batch of envs, sampled as one buffer,
    with optional n-step returns.

    ``add(i, ...)`` appends env ``i``'s transition to its own ring (so each ring holds whole
    episodes and the frame deduplication works). ``sample(B)`` draws B transitions spread evenly
    over the rings (the first ``B % N`` rings give one more). With ``n_step`` > 1, transition t's
    reward becomes sum_{j<m} gamma^j r_{t+j} over the m <= n_step steps left in its episode (fewer
    only at the episode's end or at the newest transitions), next_obs is that of step t+m-1,
    ``not_done`` is that step's, and a ``discount`` column holds gamma^m for the bootstrap.
    With one env and ``n_step`` 1 it samples exactly as its single ring does.
    """

    def __init__(self, num_envs: int, capacity: int, image_size: int = 100, frame_history: int = 5,
                 mask_dim: int = 30, proprio_dim: int = 4, action_dim: int = 5, n_step: int = 1,
                 gamma: float = 0.99, device: str | torch.device = "cpu", seed: int | None = None,
                 state_dim: int = 0, frame_offsets: tuple[int, ...] | None = None, mask_bytes: int = 0):
        if num_envs < 1 or n_step < 1:
            raise ValueError(f"MultiReplay num_envs={num_envs}, n_step={n_step}; allowed: >= 1 each")
        self.n_step, self.gamma = int(n_step), float(gamma)
        per_env = max(1, int(capacity) // int(num_envs))
        self.buffers = [ReplayBuffer(per_env, image_size, frame_history, mask_dim, proprio_dim, action_dim,
                                     device=device, seed=None if seed is None else seed + 104_729 * i,
                                     state_dim=state_dim, frame_offsets=frame_offsets, mask_bytes=mask_bytes)
                        for i in range(num_envs)]
        self.device = torch.device(device)

    def __len__(self) -> int:
        return sum(len(b) for b in self.buffers)

    def add(self, env_index: int, obs: dict, action, reward: float, next_obs: dict, terminated: bool,
            truncated: bool) -> None:
        self.buffers[env_index].add(obs, action, reward, next_obs, terminated, truncated)

    def new_episode(self) -> None:
        for b in self.buffers:
            b.new_episode()

    def begin_mid_episode(self, env_index: int, obs: dict) -> None:
        self.buffers[env_index].begin_mid_episode(obs)

    def end_episodes(self) -> None:
        """Cut every ring's running episode: its last transition becomes truncated (n-step returns
        stop there and bootstrap) and the next ``add`` starts a new episode."""
        for b in self.buffers:
            if b.in_episode and b.n_added:
                b.truncated[(b.n_added - 1) % b.capacity] = True
            b.new_episode()

    def sample(self, batch_size: int) -> dict[str, torch.Tensor]:
        """A batch (see :meth:`ReplayBuffer.sample`, plus ``discount`` when n-step or several rings)."""
        if len(self.buffers) == 1 and self.n_step == 1:
            return self.buffers[0].sample(batch_size)
        n = len(self.buffers)
        sizes = [batch_size // n + (1 if i < batch_size % n else 0) for i in range(n)]
        parts = [self._sample_n_step(b, s) for b, s in zip(self.buffers, sizes) if s > 0 and len(b) > 0]
        if not parts:
            raise ValueError("cannot sample from an empty MultiReplay")
        return {k: torch.cat([p[k] for p in parts]) for k in parts[0]}

    def sample_at(self, env_index: int, indices) -> dict[str, torch.Tensor]:
        """The n-step transitions starting at absolute ``indices`` of ring ``env_index``."""
        return self._sample_n_step(self.buffers[env_index], 0, indices)

    def latest(self, env_index: int, count: int) -> dict[str, torch.Tensor]:
        """Ring ``env_index``'s newest ``count`` one-step transitions, oldest first, whatever
        ``n_step`` (see :meth:`ReplayBuffer.latest`)."""
        return self.buffers[env_index].latest(count)

    def _sample_n_step(self, buf: ReplayBuffer, batch_size: int,
                       indices: np.ndarray | None = None) -> dict[str, torch.Tensor]:
        first = buf.sample_indices(batch_size) if indices is None else np.asarray(indices, np.int64)
        batch_size = len(first)
        last = first.copy()
        reward = np.zeros(batch_size, np.float64)
        discount = np.ones(batch_size, np.float64)
        open_ = np.ones(batch_size, bool)  # the episode goes on after step `last`
        for j in range(self.n_step):
            idx = first + j
            use = open_ & (idx < buf.n_added)
            i = idx[use] % buf.capacity
            reward[use] += discount[use] * buf.reward[i]
            discount[use] *= self.gamma
            last[use] = idx[use]
            ended = np.zeros(batch_size, bool)
            ended[use] = buf.terminated[i] | buf.truncated[i]
            open_ &= use & ~ended
        obs_stack, _ = buf.stacks(first)
        _, next_stack = buf.stacks(last)
        i0, i1 = first % buf.capacity, last % buf.capacity

        def put(a: np.ndarray) -> torch.Tensor:
            return torch.from_numpy(np.ascontiguousarray(a)).to(self.device)

        batch = {
            "obs_depth": put(obs_stack), "next_obs_depth": put(next_stack),
            "mask": put(buf.masks(i0)), "proprio": put(buf.proprio[i0]),
            "next_mask": put(buf.masks(i1, nxt=True)), "next_proprio": put(buf.next_proprio[i1]),
            "action": put(buf.action[i0]), "reward": put(reward.astype(np.float32)[:, None]),
            "not_done": put((~buf.terminated[i1]).astype(np.float32)[:, None]),
            "discount": put(discount.astype(np.float32)[:, None]),
            "index": torch.from_numpy(first),
        }
        if buf.state_dim:  # the state of the step whose next_obs the target bootstraps from
            batch["state"], batch["next_state"] = put(buf.state[i0]), put(buf.next_state[i1])
        return batch

    def state_dict(self) -> dict:
        if len(self.buffers) == 1:
            return self.buffers[0].state_dict()
        return {"format": "egosearch-multi-replay-v1", "buffers": [b.state_dict() for b in self.buffers]}

    def load_state_dict(self, state: dict) -> None:
        if len(self.buffers) == 1:
            self.buffers[0].load_state_dict(state)
            return
        if state.get("format") != "egosearch-multi-replay-v1" or len(state["buffers"]) != len(self.buffers):
            raise ValueError(f"replay state does not hold {len(self.buffers)} env rings")
        for b, s in zip(self.buffers, state["buffers"]):
            b.load_state_dict(s)


def proportional_counts(sizes: list[int], batch_size: int) -> list[int]:
    """``batch_size`` split over sources in proportion to ``sizes`` (largest remainders get the rest)."""
    total = sum(sizes)
    exact = [batch_size * s / total for s in sizes]
    counts = [int(x) for x in exact]
    for i in sorted(range(len(sizes)), key=lambda i: exact[i] - counts[i], reverse=True)[:batch_size - sum(counts)]:
        counts[i] += 1
    return counts
