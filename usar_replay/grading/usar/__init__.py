"""The course's live-demo rubric (60 points), pure: messages in, verdicts out. Rubric usar v4.

Why pure: the rubric is the part of usar a TA argues about, so it must be readable and testable
on its own, without a log file, mcap or a simulator. Nothing here reads a file or imports mcap;
:mod:`usar_replay.grading.grade` opens a log and feeds it here, ``usar replay --grade`` feeds the
replayed outputs, and the tests feed hand-made message streams.

The shape is the course's: section 9 of the handout asks five questions, and each has a module
of its own; the TA's rules and their sources are data (:mod:`.rules`), the thresholds a grader
may change are :class:`usar_replay.core.settings.Thresholds`, and every line's ``rule`` says which
rule it applied.

* :mod:`.observations`: :class:`Observations`, the streaming consumer (bounded state);
* :mod:`.follow`: whether a broadcast frame follows the detections it is sent on;
* :mod:`.targets` (Q1, targets reached), :mod:`.detection` (Q2, markers detected),
  :mod:`.broadcast` (Q3, properly broadcast, as a TA sees the frames in RViz),
  :mod:`.follower` (Q4, the follower's visits in ID order and home), :mod:`.timing` (Q5, 10
  minutes), :mod:`.commands` (two publishers on one robot: no points);
* :mod:`.judge`: every line in order, :class:`Grader` (the observations with the report), and
  :data:`RUBRIC`.

===================================  ======  ===================================================
line (``Check.id``)                  points  passes when (v4, issues 43 and 50: the TA's rules)
===================================  ======  ===================================================
``explorer.target_k``                12      the explorer came within ``target_reached_m`` (or
                                             its own goal tolerance, at most 0.4 m, +
                                             ``goal_slack_m``) of target_k after the earlier
                                             targets it reached
``marker_k.detected``                12      the course's detector's ``/fiducial_transforms``
                                             (trusted; never a mission's) holds ID k in a frame
                                             taken while the explorer was at a target (a ROS
                                             1 package: and a frame of it follows them)
``marker_k.broadcast``               8       every frame broadcast on ``/tf`` as a detection of
                                             k (any name but the simulator's, within
                                             ``detection_recent_s`` after one), placed in
                                             ``map`` at the median of its broadcasts while the
                                             explorer scanned at a target, is within
                                             ``marker_map_error_m`` of the marker (a stand-off
                                             frame alone that follows the detections: half; a
                                             frame that ignores them: nothing)
``marker_frame.only_on_detection``   4       something was broadcast, every broadcast is a
                                             child of the camera's optical frame, made within
                                             ``detection_recent_s`` after a non-empty
                                             detection, none is a stored pose sent again
                                             after an empty one, none of a frame that ignores
                                             the detections
``explorer.home_before_follower``    4       after its last target the explorer came within
                                             ``home_m`` of its start before the follower moved
``follower.marker_k``                12      the follower *stopped* within the handout's
                                             stand-off (in x and y) + its goal tolerance
                                             (at most 0.4 m) +
                                             ``goal_slack_m`` of marker k, after the lower IDs
``follower.home``                    4       the follower left home and came back, after the
                                             explorer was home
``time_limit``                       4       the follower was home within the time limit
===================================  ======  ===================================================

Points are scaled per item when a scenario has more or fewer than four targets/markers.
"""

from __future__ import annotations

from usar_replay.grading.usar.broadcast import (
    FramePlace,
    frame_places,
    marker_broadcast,
    only_on_detection,
)
from usar_replay.grading.usar.commands import one_cmd_vel_publisher
from usar_replay.grading.usar.detection import marker_detected
from usar_replay.grading.usar.follower import (
    explorer_home_before_follower,
    follower_home,
    follower_markers,
)
from usar_replay.grading.usar.judge import RUBRIC, Grader, judge
from usar_replay.grading.usar.observations import (
    DETECTION_MEMORY_NS,
    GRADE_TOPICS,
    MAX_FRAMES,
    MAX_SAMPLES,
    MAX_VISITS,
    NO_DETECTOR,
    REQUIRED_TOPICS,
    Disc,
    Observations,
)
from usar_replay.grading.usar.rules import RUBRIC_VERSION, RULES, Rule
from usar_replay.grading.usar.targets import explorer_targets, in_order
from usar_replay.grading.usar.timing import time_limit

__all__ = [
    "DETECTION_MEMORY_NS",
    "GRADE_TOPICS",
    "MAX_FRAMES",
    "MAX_SAMPLES",
    "MAX_VISITS",
    "NO_DETECTOR",
    "REQUIRED_TOPICS",
    "RUBRIC",
    "RUBRIC_VERSION",
    "RULES",
    "Disc",
    "FramePlace",
    "Grader",
    "Observations",
    "Rule",
    "explorer_home_before_follower",
    "explorer_targets",
    "follower_home",
    "follower_markers",
    "frame_places",
    "in_order",
    "judge",
    "marker_broadcast",
    "marker_detected",
    "one_cmd_vel_publisher",
    "only_on_detection",
    "time_limit",
]
