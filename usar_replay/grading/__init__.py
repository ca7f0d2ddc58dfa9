"""grading: the rubrics and what they produce.

``verdict`` (a rubric line and a grade, neutral), the US&R and ROS 2 final-project rubrics (pure
code over messages), ``rubrics`` (the one registry: an assignment's name -> its rubric; the
assignment itself is :mod:`usar_replay.world.assignment`), ``grade`` (a log in, a grade out; or
a log graded as it is written), ``reports`` (table, JSON, JUnit, CSV) and ``htmlreport``. It may
import ``core``, ``world`` and ``log``.
"""
