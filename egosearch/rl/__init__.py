"""SAC + CURL for the search policy (paper 4.2, Table 2).

- :mod:`egosearch.rl.config`: ``SacCurlConfig`` (every Table 2 value), ``PROFILES``
  (smoke / cpu / paper), ``load_config(profile, overrides)``, ``table2_rows(cfg)``;
- :mod:`egosearch.rl.sac_curl`: ``SacCurlAgent`` (``act``, ``update``, ``state_dict``,
  ``actor_state``) and the networks;
- :mod:`egosearch.rl.replay`: ``ReplayBuffer`` storing each depth frame once, ``replay_gb``;
- :mod:`egosearch.rl.train`: ``train(env_id, cfg, out_dir, env_kwargs, evaluate_fn)``
  (resumable) and ``ActorPolicy`` (loads ``actor.pt``);
- :mod:`egosearch.rl.bench`: ``bench_learner()``.

Nothing is imported here, so ``import egosearch.rl`` does not load torch.
"""
