"""An update captured as CUDA graphs and replayed (``LearnerConfig.cuda_graph``).

On a GPU a Table 2 update is hundreds of small kernels launched one after the other from Python;
the GPU spends most of the update waiting for the next launch (docs/gpu.md). A CUDA graph records
those launches once and replays them with one call, so the update costs about its kernels' time.

An update does different things on different steps (the actor and the Polyak step every
``actor_update_freq`` / ``critic_target_update_freq`` updates), so each pattern of flags gets its
own graph, keyed by the caller. What replaying needs, and how this class provides it:

- fixed input addresses: every batch is copied into static tensors owned here before a replay;
- a warmed-up update: the first ``warmup`` updates of each key run eagerly on a side stream
  (they are real updates), which creates the optimisers' state and lets cuBLAS/cuDNN pick their
  kernels before anything is recorded;
- optimisers that can be recorded: ``torch.optim.Adam(capturable=True)``, whose step counter
  lives on the device;
- random numbers drawn inside the graph from torch's CUDA generator, which advances its offset
  at every replay (crop offsets and policy noise stay fresh).

Recording runs nothing, so the update in which a graph is captured replays it at once. Replaced
optimiser state or parameters (a checkpoint loaded) invalidate the graphs: call :meth:`reset`.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable

import torch


class GraphedUpdate:
    """``graphed(key, batch)`` runs ``fn(batch) -> dict[str, Tensor]`` eagerly for the first
    ``warmup`` calls of each ``key``, then as that key's captured CUDA graph."""

    def __init__(self, fn: Callable[[dict[str, torch.Tensor]], dict[str, torch.Tensor]], warmup: int = 2):
        self.fn = fn
        self.warmup = int(warmup)
        self.reset()

    def reset(self) -> None:
        """Forget every graph (their memory is freed); the next calls warm up and capture again."""
        self.graphs: dict[Hashable, tuple[torch.cuda.CUDAGraph, dict[str, torch.Tensor]]] = {}
        self.calls: dict[Hashable, int] = {}
        self.static_batch: dict[str, torch.Tensor] | None = None
        self.captures = 0

    def _fill_static(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        on_device = {k: v for k, v in batch.items() if torch.is_tensor(v) and v.is_cuda}
        if self.static_batch is None:
            self.static_batch = {k: torch.empty_like(v) for k, v in on_device.items()}
        if self.static_batch.keys() != on_device.keys() or any(
                self.static_batch[k].shape != v.shape or self.static_batch[k].dtype != v.dtype
                for k, v in on_device.items()):
            raise ValueError("a graphed update needs every batch to have the same keys, shapes and dtypes "
                             f"(first: { {k: tuple(v.shape) for k, v in self.static_batch.items()} }, "
                             f"now: { {k: tuple(v.shape) for k, v in on_device.items()} })")
        for k, v in on_device.items():
            self.static_batch[k].copy_(v, non_blocking=True)
        return {**batch, **self.static_batch}

    def __call__(self, key: Hashable, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        graphed = self.graphs.get(key)
        if graphed is not None:
            self._fill_static(batch)
            graphed[0].replay()
            return graphed[1]
        static = self._fill_static(batch)
        calls = self.calls.get(key, 0)
        self.calls[key] = calls + 1
        if calls < self.warmup:
            side = torch.cuda.Stream()
            side.wait_stream(torch.cuda.current_stream())
            with torch.cuda.stream(side):
                out = self.fn(static)
            torch.cuda.current_stream().wait_stream(side)
            return out
        graph = torch.cuda.CUDAGraph()
        with torch.cuda.graph(graph):
            out = self.fn(static)
        self.graphs[key] = (graph, out)
        self.captures += 1
        graph.replay()
        return out
