"""The simulation: the pybullet world, depth+mask sensor, pictures, navigation grid, floor map, scenarios, env.
Imports: core, scene.
Imported by: cli, envs, motion, rl, runs, searchers, variants.
Packages: embreex, gymnasium, matplotlib, numpy, pyrender, scipy, tqdm, trimesh."""
