"""The search policy's learners (paper 4.2, Table 2), their training loop and their actor files.
Imports: core, envs, runs, scene, searchers, sim.
Imported by: cli, cost, variants.
Packages: gymnasium, numpy, torch, tqdm.
searchers for the teacher, runs for the curve evaluations; the cost model reads the env step units and the
learner benchmark.

- :mod:`egosearch.rl.config`: ``LearnerConfig`` (the run settings and the learner's own, composed: one
  config class per learner), ``load_config(preset, overrides)``, ``table2_rows(cfg)``, ``departure_rows(cfg)``;
- :mod:`egosearch.rl.config_page`: the docs site's page of every learner's fields (``egosearch config page``);
- :mod:`egosearch.rl.run_settings`: ``RunSettings``, what every learner and the training loop share;
- :mod:`egosearch.rl.training_aids`: the aids a learner's settings opt into (``DemonstrationSettings``,
  ``PrivilegedCriticSettings``) and how the loop reads them for any learner (``demonstration_settings``,
  ``critic_reads_state``);
- :mod:`egosearch.rl.network_settings`: the pieces each learner's own settings are made of (``NetworkSettings``,
  ``SacSettings``, ``PooledSettings``, ``RandomShiftSettings``);
- :mod:`egosearch.rl.sac_curl_settings`, :mod:`egosearch.rl.sac_drq_settings`,
  :mod:`egosearch.rl.sac_drq_recurrent_settings`, :mod:`egosearch.rl.ppo_settings`: each learner's own
  settings, registered with it in the registry;
- :mod:`egosearch.rl.presets`: ``PRESETS`` (smoke / cpu / paper) as data, with their sources;
- :mod:`egosearch.rl.learner_registry`: the learners by name (``LEARNERS``, ``register``, ``make_agent``),
  the settings class of each and the actor file formats they write (``actor_loader``); adding a learner
  is one module (and its settings') and one ``register`` line there;
- :mod:`egosearch.rl.learner`: ``Agent``, the protocol the training loop and ``AgentPolicy`` drive,
  and ``AgentBase``, its optional hooks' defaults; the actor file's contract (``ActorFile``,
  ``ActorArch``, ``ActorFileNet``);
- :mod:`egosearch.rl.common`: what every learner builds from (actor head, layers, crops,
  observation tensors, update metrics, actor weights);
- :mod:`egosearch.rl.pooled`: what the pooled-depth learners share (``PooledConvEncoder``,
  ``pool_depth``, ``drq_arch``, ``act_with``, SAC-DrQ's actor file, ``PooledAgent``) and ``SacMixin``
  (SAC's temperature and actor step);
- :mod:`egosearch.rl.sac_curl`: ``SacCurlAgent`` and its networks (the paper's learner);
- :mod:`egosearch.rl.sac_drq`: ``SacDrqAgent``, SAC with a DrQ-v2-style update (the cpu preset's), and
  ``SacDrqBase``, its SAC set-up and Polyak step, which the recurrent form builds on;
- :mod:`egosearch.rl.sac_drq_recurrent`: ``SacDrqRecurrentAgent``, SAC-DrQ with a GRU in the actor
  and another in the critic, trained on replayed sequences with burn-in (not the paper's algorithm);
- :mod:`egosearch.rl.ppo`: ``PpoAgent``, PPO on SAC-DrQ's actor with a separate value network, trained
  on each env's latest rollout (on-policy; not the paper's algorithm);
- :mod:`egosearch.rl.replay`: ``ReplayBuffer`` storing each depth frame once, ``MultiReplay``
  (one ring per env, n-step returns), ``replay_gb``;
- :mod:`egosearch.rl.train`: ``train(env_id, cfg, out_dir, env_kwargs, evaluate_fn)``
  (resumable; its loop's steps are the methods of ``LiveRun``);
- :mod:`egosearch.rl.stacked`: ``StackedAgents`` (``stack_agents``): N seeds' updates as one stacked,
  vmapped model, each seed drawing from its own ``SeedStreams``; equal to N separate updates;
- :mod:`egosearch.rl.train_stacked`: ``train_stacked(env_id, cfgs, out_dirs)``: one ``LiveRun`` per
  seed (its own envs, replay, streams and files), their updates stacked;
- :mod:`egosearch.rl.train_env`: the training envs (``make_train_env``, ``train_env_kwargs``: the
  variant's env with the config's training aids);
- :mod:`egosearch.rl.demos`: the frontier searcher's transitions stored as a replay, the demonstrations
  (``collect_demonstrations``, ``load_demonstrations``);
- :mod:`egosearch.rl.imitation`: behaviour cloning on them (``clone``) and DAgger rounds
  (``dagger_round``), before RL;
- :mod:`egosearch.rl.run_files`: the run's files (atomic writes, CSV logs, checkpoints);
- :mod:`egosearch.rl.actor`: ``ActorPolicy`` (loads any learner's ``actor.pt``) and ``AgentPolicy``
  (a live agent behind the policy interface);
- :mod:`egosearch.rl.cuda_graph`: ``GraphedUpdate`` (an update recorded as CUDA graphs);
- :mod:`egosearch.rl.bench_learner`: ``bench_learner()`` and ``gpu_check()``.

Nothing is imported here, so ``import egosearch.rl`` does not load torch.
"""
