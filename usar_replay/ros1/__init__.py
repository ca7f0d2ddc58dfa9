"""ros1: run a course's ROS 1 catkin package, unmodified, against usar's world.

Two subpackages, one concern each, with their faces in ``__init__``: ``build`` (the build
side: the Debian packages a course machine has, the ROS -> Debian table for hints, usar's
stand-ins for what it replaces, the underlay and the overlay workspace, the jail, the cache,
``build_failed`` and its hint) and ``pacing`` (the clock side: when ``/clock`` may start and
advance, idle detection, the preloaded shim for busy-polling nodes, shutdown holds, the graph's
CPU set). Beside them, what stands on both: ``launch_filter`` and ``launch_output`` (the team's
launch file with usar's stand-ins in place of what it replaces), ``netns`` (the bridge in its
own network namespace), ``process`` (the recorder's side: the bridge takes the mission
process's place), ``bridge`` (the bridge process: the tick protocol to the recorder, ROS 1 to
the student's graph), ``convert`` (usar's ROS 2 message values <-> rospy's), ``move_base``
(actionlib servers backed by usar's navigator), ``boundary`` and ``topic_recorder`` (what
crosses from the graph, checked), ``run_files`` (the run folder's files read back), ``record``
(``usar record --ros1``) and ``replay``.

It may import ``core``, ``world``, ``log``, ``sim``, ``node``, ``grading`` and ``pipeline``.
rospy and the generated ROS 1 messages are imported only inside the bridge process (Debian's
``/usr/lib/python3/dist-packages`` is appended to its ``sys.path``), so importing this layer
needs no ROS at all; the catkin packages usar ships live in ``build/catkin/``.
"""
