"""node: the rclpy-shaped node API a mission is written on.

``node`` (Node, publishers, subscriptions, timers, parameters), ``executor`` (the deterministic
callback order), ``tf2`` (tf2_ros bound to a node), ``navigation`` (the move_base-like client)
and ``boundary_check`` (the check of everything a mission sends: sizes, counts, types, finite
values; the executor and the recorder both apply it). A mission process loads this layer: it may
import ``core`` and ``world`` and loads no pybullet, mcap or rerun. Mission authors import
:mod:`usar_replay.api`, not these modules. The process that runs a mission is :mod:`usar_replay.
process`; the sandbox it runs in is :mod:`usar_replay.sandbox`.
"""
