"""Full-body characters for the abstract search policy (paper section 5): motion generators and Algorithm 1.
Imports: core, runs, scene, sim.
Imported by: cli.
Packages: PIL, imageio, numpy, pybullet_data, pyrender, tqdm, trimesh.
The policy comes in as a callable.

- :mod:`~egosearch.motion.mocap`: DeepMimic clips from pybullet_data;
- :mod:`~egosearch.motion.humanoid` (1.65 m DeepMimic humanoid), :mod:`~egosearch.motion.fetch`;
  :mod:`~egosearch.motion.skeleton` (the humanoid's URDF in numpy), :mod:`~egosearch.motion.quat`
  (quaternions in pybullet's order);
- :mod:`~egosearch.motion.base`: ``FullBodyPose`` and the ``MotionGenerator`` interface;
  :mod:`~egosearch.motion.phase` (``PhaseMG``), :mod:`~egosearch.motion.matching` (``MatchingMG``),
  ``FetchMG``;
- :mod:`~egosearch.motion.replan`: Algorithm 1, baselines, ``evaluate_fullbody``;
- :mod:`~egosearch.motion.collision`: ``PenetrationCounter``, the full body's penetration of the home;
- :mod:`~egosearch.motion.video`: first-person + third-person search videos.
"""

from egosearch.motion.replan import (  # noqa: F401
    DEFAULT_M,
    DEFAULT_T,
    FULLBODY_COLUMNS,
    M_VALUES,
    METHODS,
    MOTION_GENERATORS,
    evaluate_fullbody,
    run_fullbody_episode,
    write_fullbody,
)
