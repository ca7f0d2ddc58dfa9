"""The TA's rules of the course's live demo as data, each with its source.

Why a module of its own: these numbers are what a TA argues about. Each comes from the
handout, the course template's parameters or a measurement, and says which; the rubric's lines
(:mod:`.targets`, :mod:`.detection`, :mod:`.broadcast`, :mod:`.follower`, :mod:`.timing`) read
them from here, and each line's ``rule`` names the rule it applied. The thresholds a grader may
change (``[thresholds]``) are :class:`usar_replay.core.settings.Thresholds`; these are the
rubric's own.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "BROADCAST_MATCH_M",
    "FOLLOW_MATCH_M",
    "MAX_GOAL_TOLERANCE_M",
    "ONE_PLACE",
    "RUBRIC_VERSION",
    "RULES",
    "SCAN_TURN_RAD_S",
    "STEADY",
    "TEMPLATE_GOAL_TOLERANCE_M",
    "Rule",
]

RUBRIC_VERSION = 4
"""1: only ``marker_frame`` was a broadcast, stamped exactly with a detected image's stamp.
2 (issue #32): a frame of any name on ``/tf`` (not the simulator's), stamped within one camera
period after a detected image (or zero: when it was sent), placed in ``map`` through its parent
at that stamp; the broadcast line shows the frame a TA would look at.
3 (issue 43, the TA's rules): a follower visit is a *stop* within the handout's stand-off plus
the package's move_base goal tolerance; home and time stand on their own; a marker's broadcast
is the median place of its frames broadcast while the explorer was at a target, within the
camera's reliable range (a stand-off frame earns half, the worst frame decides); a broadcast is
"on a detection" when a non-empty detection came within ``detection_recent_s`` before it (and it
is not a stored pose sent again after an empty one); a detection counts when the explorer was
at a target.
4 (issue 50, no package setting widens the rubric beyond a TA's eye): a package's move_base
goal tolerance widens the radii by at most :data:`MAX_GOAL_TOLERANCE_M`; a stand-off frame earns
its half only where it follows the detections (:mod:`.follow`), a frame that ignores them breaks
``only_on_detection`` and earns nothing; a ROS 1 package's detections count only where one of
its frames follows them; (issue 51, the TA's clock) nothing observed after the world's time limit
scores on any line (:func:`.timing.seen_by_the_ta`)."""
TEMPLATE_GOAL_TOLERANCE_M = 0.05
"""The course template's move_base ``xy_goal_tolerance`` (``dwa_local_planner_params.yaml``):
a robot's goal tolerance where neither the thresholds nor the log say another."""
MAX_GOAL_TOLERANCE_M = 0.4
"""The most of a package's own move_base ``xy_goal_tolerance`` the rubric's radii take (a
target's, a marker's visit, "at a target" for a detection). Source: the handout, section 6:
"I suggest you task follower to reach those markers within a tolerance (0.4m seems to be
good)" (``shared/seeds``' handout text; course-world.md, Mission rules). A package may set 10 m,
and usar's move_base then stops its robot up to 10 m short, as the course's would; but a TA
watching a robot stop 3 m from a target does not say it reached it (issue 50: a package that
never moved scored 36/60 with ``xy_goal_tolerance: 10.0``). So a target is reached within at
most 0.4 + 0.10 m, a marker visited within at most 0.57 + 0.4 + 0.10 m."""
SCAN_TURN_RAD_S = 0.5
"""Faster than this the explorer is not scanning but turning to a goal: the course's scans
spin at 0.1-0.3 rad/s, move_base turns at up to about 2 rad/s (issue 43's packages)."""
STEADY = 0.5
"""A frame is on the marker when its median place is, and at least this share of its deciding
broadcasts are (a frame that flickers between the marker and elsewhere is not)."""
BROADCAST_MATCH_M = 0.005
"""How close a broadcast must be to a detection in its window (in the camera frame) to be
that detection's broadcast. A broadcaster copies the detected pose, so an honest one is exact;
a copy of an older frame's detection stamped "now" is off by the turn since that frame (about
1-2.5 cm at 0.1 rad/s and 10 Hz, 1-2.5 m away) and is, exactly, that older detection."""

FOLLOW_MATCH_M = 0.02
"""How exactly a frame must follow a detection (:mod:`.follow`): its origin on the line from
the camera to the detected marker within this, or its offset from the detected pose the same
vector (in the detection's axes or in ``map``'s) within this at its broadcasts. A package
computes its frame from the detection it got, so an honest one is exact up to the turn between
its tf lookups (about 4 mm at 0.1 rad/s, 0.4 m out); a frame put at a fixed place ahead of the
camera is off the line by centimetres to decimetres wherever the marker is not dead ahead."""
ONE_PLACE = 0.9
"""A frame (or the detections it was sent on) stays at one place in the camera frame when this
share of its broadcasts lie within :data:`FOLLOW_MATCH_M` of their median: a frame that stays
while the detections move ignores them."""


@dataclass(frozen=True, slots=True)
class Rule:
    """One TA rule: the section-9 question it answers, the rule in a few words (what a line's
    ``rule`` says) and where it comes from."""

    question: str
    says: str
    source: str

    @property
    def text(self) -> str:
        """The rule as a line's ``rule`` says it: question, rule, source."""
        return f"{self.question}: {self.says} (source: {self.source})"


RULES: dict[str, Rule] = {
    "targets": Rule(
        "Q1 targets reached",
        "the explorer within 0.15 m of each target in order, or its goal tolerance (<= 0.4) "
        "+ 0.1 m",
        "v2's radius: the template's 0.05 m xy_goal_tolerance plus the controller's overshoot; "
        "handout section 6's 0.4 m tolerance the most a package's own widens it",
    ),
    "detected": Rule(
        "Q2 markers detected",
        "the course's detector saw it while the explorer was at a target; a package's frame "
        "follows it",
        "handout section 4: the explorer spins at each target until it sees the marker",
    ),
    "broadcast": Rule(
        "Q3 properly broadcast",
        "each frame's median place at a target within 10 cm (a stand-off that follows it: half)",
        'handout section 9: "We will take a look at the frames in RViz"',
    ),
    "only_on_detection": Rule(
        "Q3 properly broadcast",
        "every broadcast within 2 s after a detection, none a stored pose, none ignoring it",
        'handout section 5: "broadcast this Frame only when the marker is detected"',
    ),
    "explorer_home": Rule(
        "Q4 follower",
        "the explorer home after its last target, before the follower moves",
        "handout section 6: the follower starts once the explorer is home",
    ),
    "visits": Rule(
        "Q4 follower visits in ID order",
        "a stop within 0.4 m in x and y of the marker plus the goal tolerance (<= 0.4) + 0.1 m",
        'handout section 6: "within a tolerance (0.4m seems to be good)"; the package\'s move_base',
    ),
    "follower_home": Rule(
        "Q4 follower home",
        "the follower left home and came back after the explorer was home",
        "handout section 6",
    ),
    "time_limit": Rule(
        "Q5 10 minutes",
        "the follower home within the world's time limit (600 s in the course)",
        'handout section 9: "10 minutes"',
    ),
    "cmd_vel": Rule(
        "(no points)",
        "one moving command per tick and robot",
        "team 002's report: a spin timer fighting the navigator",
    ),
}
"""Each line family's rule (:attr:`usar_replay.grading.verdict.Check.rule`)."""
