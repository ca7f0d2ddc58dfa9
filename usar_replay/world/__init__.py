"""world: the course's world as data and the infrastructure the course provides.

The scenario model (``scenario``) and its TOML file (``scenario_toml``), the assignments
(``assignment``: one object each, world, robots, parameters, default mission; the registry that
packages add to), seeded variants (keyed by a secret world key: ``world_key``), the ROS 2 final
project's world, the scenario checks, the planner (move_base's role) and the ArUco detector
(aruco_detect's role). Pure code over data: it may import only ``core`` and loads no pybullet,
mcap or rerun.
"""
