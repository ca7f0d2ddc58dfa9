"""core: the shared facts and codecs every process needs.

The log contract (topics, frames, keys, the robot body), ROS 2 messages as typed values and
their CDR codecs, finite values only (``finite``), rotations, the tf2-exact buffer, every
setting and its TOML codec, the one error hierarchy, atomic output files and signal handling. It
imports nothing of usar's and loads no pybullet, mcap or rerun: the mission process loads it
too.
"""
