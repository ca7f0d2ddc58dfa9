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
    "RUBRIC_VERSION",
    "RULES",
    "SCAN_TURN_RAD_S",
    "STEADY",
    "TEMPLATE_GOAL_TOLERANCE_M",
    "Rule",
]

RUBRIC_VERSION = 3
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
at a target."""
TEMPLATE_GOAL_TOLERANCE_M = 0.05
"""The course template's move_base ``xy_goal_tolerance`` (``dwa_local_planner_params.yaml``):
a robot's goal tolerance where neither the thresholds nor the log say another."""
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
        "the explorer within 0.15 m of each target in order, or its own goal tolerance + 0.10 m",
        "v2's radius: the template's 0.05 m xy_goal_tolerance plus the controller's overshoot",
    ),
    "detected": Rule(
        "Q2 markers detected",
        "the course's detector saw the marker while the explorer was at a target",
        "handout section 4: the explorer spins at each target until it sees the marker",
    ),
    "broadcast": Rule(
        "Q3 properly broadcast",
        "each frame's median place while the explorer scans at a target, within 10 cm",
        'handout section 9: "We will take a look at the frames in RViz"',
    ),
    "only_on_detection": Rule(
        "Q3 properly broadcast",
        "every broadcast within 2 s after a non-empty detection, no stored pose sent again",
        'handout section 5: "broadcast this Frame only when the marker is detected"',
    ),
    "explorer_home": Rule(
        "Q4 follower",
        "the explorer home after its last target, before the follower moves",
        "handout section 6: the follower starts once the explorer is home",
    ),
    "visits": Rule(
        "Q4 follower visits in ID order",
        "a stop within 0.4 m in x and y of the marker plus the goal tolerance + 0.10 m",
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
