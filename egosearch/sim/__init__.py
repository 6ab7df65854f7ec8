"""The simulation: the pybullet world, depth+mask sensor, pictures, navigation grid, floor map, scenarios, env.
Imports scene/ and core/; imported by searchers/, rl/, runs/, motion/ and the CLI."""
