"""The learners by name: ``cfg.algorithm`` -> the agent the training loop builds."""

from __future__ import annotations

from egosearch.rl.config import LearnerConfig
from egosearch.rl.sac_curl import SacCurlAgent

ALGORITHM_NAMES = {"sac_curl": "SAC+CURL", "sac_drq": "SAC-DrQ", "sac_drq_recurrent": "recurrent SAC-DrQ",
                    "ppo": "PPO"}


def make_agent(cfg: LearnerConfig, action_dim: int, mask_dim: int, proprio_dim: int, device,
               state_dim: int = 0):
    """The learner ``cfg.algorithm`` names (both share act / update / state_dict / actor_state);
    ``state_dim``: size of the env's privileged state (``critic_privileged_state``)."""
    if cfg.algorithm == "ppo":
        from egosearch.rl.ppo import PpoAgent

        return PpoAgent(cfg, action_dim, mask_dim, proprio_dim, device=device, state_dim=state_dim)
    if cfg.algorithm == "sac_drq_recurrent":
        from egosearch.rl.sac_drq_recurrent import SacDrqRecurrentAgent

        return SacDrqRecurrentAgent(cfg, action_dim, mask_dim, proprio_dim, device=device, state_dim=state_dim)
    if cfg.algorithm == "sac_drq":
        from egosearch.rl.sac_drq import SacDrqAgent

        return SacDrqAgent(cfg, action_dim, mask_dim, proprio_dim, device=device, state_dim=state_dim)
    return SacCurlAgent(cfg, action_dim, mask_dim, proprio_dim, device=device)
