"""The search policy's learners (paper 4.2, Table 2): SAC + CURL, and the cpu profile's SAC-DrQ.

- :mod:`egosearch.rl.config`: ``LearnerConfig`` (every Table 2 value and every learner's knobs),
  ``PROFILES`` (smoke / cpu / paper), ``load_config(profile, overrides)``, ``table2_rows(cfg)``;
- :mod:`egosearch.rl.common`: what both learners build from (actor head, layers, crops,
  observation tensors, update metrics, actor files);
- :mod:`egosearch.rl.sac_curl`: ``SacCurlAgent`` (``act``, ``update``, ``state_dict``,
  ``actor_state``) and its networks (the paper's learner);
- :mod:`egosearch.rl.sac_drq`: ``SacDrqAgent``, the same interface with a DrQ-v2-style update;
- :mod:`egosearch.rl.sac_drq_recurrent`: ``SacDrqRecurrentAgent``, SAC-DrQ with a GRU in the actor
  and another in the critic, trained on replayed sequences with burn-in (not the paper's algorithm);
- :mod:`egosearch.rl.ppo`: ``PpoAgent``, PPO on SAC-DrQ's actor with a separate value network, trained
  on each env's latest rollout (on-policy; not the paper's algorithm);
- :mod:`egosearch.rl.replay`: ``ReplayBuffer`` storing each depth frame once, ``MultiReplay``
  (one ring per env, n-step returns), ``replay_gb``;
- :mod:`egosearch.rl.train`: ``train(env_id, cfg, out_dir, env_kwargs, evaluate_fn)``
  (resumable; its loop's steps are the methods of ``_Run``) and ``ActorPolicy`` (loads ``actor.pt``);
- :mod:`egosearch.rl.bench`: ``bench_learner()``.

Nothing is imported here, so ``import egosearch.rl`` does not load torch.
"""
