"""node: the rclpy-shaped node API and the mission process.

``node`` (Node, publishers, subscriptions, timers, parameters), ``executor`` (the deterministic
callback order), ``tf2`` (tf2_ros bound to a node), ``navigation`` (the move_base-like client),
``worker`` (the mission process and its boundary), ``boundary_check`` (the recorder's check of
everything the mission sends: sizes, counts, types, finite values), ``jail`` (the kernel sandbox
it runs in: bubblewrap and per-run limits) and ``sandbox`` (the in-process guard, a second
layer). A mission process loads this layer: it may import ``core`` and ``world`` and loads no
pybullet, mcap or rerun. Mission authors import :mod:`usar_replay.api`, not these modules.
"""
