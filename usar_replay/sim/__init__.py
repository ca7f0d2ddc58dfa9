"""sim: the pybullet simulator (the only pybullet importer) and the camera it renders.

Builds the world from a scenario, drives the robots by ``cmd_vel``, renders and encodes the
explorer's camera. It may import ``core`` and ``world``.
"""
