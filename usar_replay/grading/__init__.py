"""grading: the rubrics and what they produce.

``verdict`` (a rubric line and a grade, neutral), the US&R and ROS 2 final-project rubrics (pure
code over messages), ``assignment`` (what differs between the two: world, robots, parameters,
default mission, rubric), ``grade`` (a log in, a grade out), ``reports`` (table, JSON, JUnit,
CSV) and ``htmlreport``. It may import ``core``, ``world`` and ``log``.
"""
