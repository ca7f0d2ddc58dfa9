"""node: the rclpy-shaped node API and the mission process.

``node`` (Node, publishers, subscriptions, timers, parameters), ``executor`` (the deterministic
callback order), ``tf2`` (tf2_ros bound to a node), ``navigation`` (the move_base-like client),
``protocol`` (the mission wire protocol: frames, pack/unpack, its version), ``mission_target``
(what ``--mission`` names, and its loader), ``mission_process`` (usar's handle on the mission
process: limits, ticks, verdicts), ``worker`` (the mission process's own side, run in the
sandbox), ``boundary_check`` (the recorder's check of everything the mission sends: sizes,
counts, types, finite values), ``kernel_sandbox`` (the kernel sandbox it runs in: bubblewrap and
per-run limits) and ``audit_guard`` (the in-process audit guard, a second layer). A mission
process loads this layer: it may import ``core`` and ``world`` and loads no pybullet, mcap or
rerun. Mission authors import :mod:`usar_replay.api`, not these modules.
"""
