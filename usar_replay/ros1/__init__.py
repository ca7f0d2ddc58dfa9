"""ros1: run a course's ROS 1 catkin package, unmodified, against usar's world.

``debian`` (the Debian packages ROS 1 needs, and the check that says what to install),
``build`` (usar's ``fiducial_msgs`` as an underlay, the package in a private overlay, the build
cache; ``build_failed``), ``buildjail`` (the build in the run's sandbox and limits),
``buildmsg`` (a failed build's errors in the student's folder, with a hint), ``tree`` (a built
workspace checked, frozen, listed and verified),
``netns`` (the one function that starts the bridge in its own network namespace),
``process`` (the recorder's side: the bridge takes the mission process's place),
``bridge`` (the bridge process: the tick protocol to the recorder, ROS 1 to the student's graph),
``convert`` (usar's ROS 2 message values <-> rospy's), ``move_base`` (actionlib servers backed
by usar's navigator) and ``record`` (``usar record --ros1``).

It may import ``core``, ``world``, ``log``, ``sim``, ``node``, ``grading`` and ``pipeline``.
rospy and the generated ROS 1 messages are imported only inside the bridge process (Debian's
``/usr/lib/python3/dist-packages`` is appended to its ``sys.path``), so importing this layer
needs no ROS at all; the catkin packages usar provides live in ``catkin/``.
"""
