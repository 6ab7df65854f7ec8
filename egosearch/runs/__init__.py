"""Running searches: a policy over a scenario CSV gives per-episode CSVs and per-step traces; the paper's metrics.
Imports: core, envs, scene, searchers, sim.
Imported by: cli, motion, rl.
Packages: gymnasium, numpy, tqdm, trimesh."""
