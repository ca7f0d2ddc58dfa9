"""pipeline: the two jobs that run a mission: ``record`` (live, in the simulator) and
``replay`` (from a log), with the replay's comparison report, and ``course_detector`` (the
course's aruco_detect on the recorder's side: detections the mission cannot forge).

They wire the simulator, the mission process, the log and the grader together: they may import
``core``, ``world``, ``log``, ``sim``, ``node`` and ``grading``.
"""
