"""The ``map_image`` observation option (:mod:`egosearch.sim.observation_options`): the map a classical searcher
plans on, given to the policy as an image around its body. A CHANGE OF OBSERVATION, never the paper's.

From the body's own depth frames and pose (habitat's GPS+compass gives the same odometry) the option builds the
floor map the frontier searcher builds (:class:`egosearch.sim.floormap.FloorMap`: free, occupied and unknown
0.1 m cells, and the cells the body stood in), and remembers where the target was last seen (from the depth under
the mask, as the env's target memory does). Each step it samples that map in a square of :data:`MAP_CELLS` x
:data:`MAP_CELLS` cells of :data:`MAP_CELL_SIZE` m around the body (8 m across: the homes' rooms and the way
between them), turning with the body (row 0 ahead, column 0 to the left), in :data:`MAP_CHANNELS` channels:

0. the share of the cell's floor seen free;
1. the share seen occupied (what is still unknown is 1 minus these two);
2. whether the body has stood in the cell this episode;
3. whether the target was last seen there.

The values are appended to ``mask`` (``4 x 32 x 32 = 4096``, channel-major), each a multiple of 1/255, so that a
replay stores them as bytes (:attr:`MapImage.byte_valued`); the learners read them as an image with a small conv
encoder of their own (:class:`egosearch.rl.common.MapReader`). After Active Neural SLAM and SemExp (Chaplot et al.
2020), whose policies read an egocentric map of what they have seen and where they have been.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from egosearch.sim.body import IMAGE_SIZE
from egosearch.sim.floormap import FREE, OCCUPIED, FloorMap
from egosearch.sim.observation_options import ObservationOption
from egosearch.sim.sensor import camera_axes, pixel_rays_camera

MAP_CELLS = 32
"""Side of the map image (cells)."""
MAP_CELL_SIZE = 0.25
"""Side of a map image cell (m): 32 of them span 8 m."""
MAP_CHANNELS = 4
"""Free share, occupied share, stood there, target last seen there (module docstring)."""
MAP_IMAGE_DIM = MAP_CHANNELS * MAP_CELLS * MAP_CELLS
"""Values the option appends to ``mask``."""
SUBSAMPLES = 3
"""Points per cell side at which the 0.1 m floor map is read (9 per cell)."""


def _sample_offsets() -> tuple[np.ndarray, np.ndarray]:
    """Body-frame (forward, left) coordinates (m) of every sample point, (MAP_CELLS * SUBSAMPLES)^2 of them."""
    n = MAP_CELLS * SUBSAMPLES
    step = MAP_CELL_SIZE / SUBSAMPLES
    along = (np.arange(n) + 0.5) * step - MAP_CELLS * MAP_CELL_SIZE / 2
    forward, left = np.meshgrid(-along, -along, indexing="ij")  # row 0 farthest ahead, column 0 farthest left
    return forward, left


class MapImage(ObservationOption):
    """The egocentric map image (module docstring)."""

    extra_dims: ClassVar[dict[str, int]] = {"mask": MAP_IMAGE_DIM}
    byte_valued: ClassVar[bool] = True
    image_shape: ClassVar[tuple[int, int, int]] = (MAP_CHANNELS, MAP_CELLS, MAP_CELLS)

    def __init__(self) -> None:
        self.map: FloorMap | None = None
        self.target: np.ndarray | None = None
        self.folded_step = -1
        self._forward, self._left = _sample_offsets()
        self._rays: np.ndarray | None = None

    def reset(self, env: Any) -> None:
        if self.map is None:
            self.map = FloorMap.for_sensor(env.sensor, pixel_stride=4, free_step=0.1)
            self._rays = pixel_rays_camera(IMAGE_SIZE, IMAGE_SIZE, env.sensor.fov_deg)
        self.map.reset()
        self.target, self.folded_step = None, -1

    def _fold(self, env: Any) -> None:
        """The env's newest frame into the map, once per env step (the replanner may observe without a step)."""
        if env.steps == self.folded_step:
            return
        self.folded_step = env.steps
        s, depth, mask = env.state, env._last_depth, env._last_mask
        self.map.update(depth, s)
        if mask is not None and mask.any():
            z = float(np.median(depth[mask])) / 255.0 * env.sensor.max_depth
            ray = self._rays[mask].mean(axis=0)
            self.target = np.asarray(s.camera_position) + camera_axes(s.camera_yaw, s.pitch).T @ (ray * z)

    def image(self, env: Any) -> np.ndarray:
        """The (MAP_CHANNELS, MAP_CELLS, MAP_CELLS) float32 image, each value a multiple of 1/255."""
        self._fold(env)
        s, floor = env.state, self.map
        c, sn = math.cos(s.theta), math.sin(s.theta)
        xs = s.x + c * self._forward - sn * self._left
        ys = s.y + sn * self._forward + c * self._left
        ox, oy = floor.origin
        rows = np.floor((ys - oy) / floor.RESOLUTION).astype(np.int64) + floor.n // 2
        cols = np.floor((xs - ox) / floor.RESOLUTION).astype(np.int64) + floor.n // 2
        inside = (rows >= 0) & (rows < floor.n) & (cols >= 0) & (cols < floor.n)
        rows, cols = np.clip(rows, 0, floor.n - 1), np.clip(cols, 0, floor.n - 1)
        grid = np.where(inside, floor.grid[rows, cols], 0)
        visited = inside & (floor.visits[rows, cols] > 0)
        k = SUBSAMPLES
        blocks = np.stack([grid == FREE, grid == OCCUPIED, visited]).reshape(3, MAP_CELLS, k, MAP_CELLS, k)
        out = np.zeros((MAP_CHANNELS, MAP_CELLS, MAP_CELLS), np.float32)
        out[:2] = blocks[:2].mean(axis=(2, 4))
        out[2] = blocks[2].any(axis=(1, 3))
        if self.target is not None:
            dx, dy = self.target[0] - s.x, self.target[1] - s.y
            forward, left = c * dx + sn * dy, -sn * dx + c * dy
            half = MAP_CELLS * MAP_CELL_SIZE / 2
            row, col = math.floor((half - forward) / MAP_CELL_SIZE), math.floor((half - left) / MAP_CELL_SIZE)
            if 0 <= row < MAP_CELLS and 0 <= col < MAP_CELLS:
                out[3, row, col] = 1.0
        # bytes in a replay, floats here: the same values either way
        return np.round(out * 255.0).astype(np.float32) / np.float32(255.0)

    def values(self, env: Any) -> dict[str, np.ndarray]:
        return {"mask": self.image(env).reshape(-1)}

    def snapshot(self) -> tuple:
        return (self.map.copy_state(), None if self.target is None else self.target.copy(), self.folded_step)

    def restore(self, state: tuple) -> None:
        floor, target, self.folded_step = state
        self.map.set_state(floor)
        self.target = None if target is None else target.copy()


@dataclass
class MapImageSettings:
    """The option's config field (every learner's config has it)."""

    map_image: bool = False
    """Paper: False (the policy sees its last 5 depth frames, the target mask and the head's pose). True: the floor
    map the tuned frontier searcher plans on, built from the policy's own depth frames and odometry, as a 4 x 32 x
    32 image of 0.25 m cells around the body (free, occupied, stood there, target last seen;
    ``egosearch.sim.map_image``), read by a small conv encoder beside the depth encoder (Active Neural SLAM and
    SemExp, Chaplot et al. 2020), after the memory-window measurement (``snakemake memory_window``: held to 5 steps
    of memory the tuned searcher falls to the student's level). An env keyword option, recorded with the run's
    config in its actor file, which ``egosearch evaluate`` reads back. This CHANGES THE OBSERVATION, for the actor
    and at evaluation too; no preset turns it on (``ablations/head_on_map_image.yaml`` screens it)."""
