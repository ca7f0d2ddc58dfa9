"""process: the mission process, both sides of its one socket.

``mission_process`` (usar's handle on it: limits, ticks, verdicts), ``worker`` (the mission's
own side, run in the sandbox), ``protocol`` and ``wire_io`` (the frames that cross the boundary
and their version), ``mission_target`` (what ``--mission`` names, and its loader) and
``log_budget`` (how much a mission may log). It may import ``core``, ``world``, ``sandbox``
(what confines the process) and ``node`` (the API the mission's code runs on); a mission process
loads it, so it loads no pybullet, mcap or rerun.
"""
