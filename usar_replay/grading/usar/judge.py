"""The rubric whole: every line in rubric order, the grader with its report, and
:data:`RUBRIC` (what the US&R assignment carries)."""

from __future__ import annotations

import math

from usar_replay.core import contract, msgs
from usar_replay.grading.usar.broadcast import (
    frame_places,
    marker_broadcast,
    only_on_detection,
    place_text,
    shown_place,
)
from usar_replay.grading.usar.commands import one_cmd_vel_publisher
from usar_replay.grading.usar.detection import marker_detected
from usar_replay.grading.usar.follower import (
    explorer_home_before_follower,
    follower_home,
    follower_markers,
)
from usar_replay.grading.usar.observations import GRADE_TOPICS, REQUIRED_TOPICS, Observations
from usar_replay.grading.usar.rules import RUBRIC_VERSION
from usar_replay.grading.usar.targets import explorer_targets, in_order, last_reached
from usar_replay.grading.usar.timing import seen_by_the_ta, time_limit
from usar_replay.grading.verdict import Check, FoundMarker, GradeReport, Rubric

__all__ = ["RUBRIC", "Grader", "judge"]


class Grader(Observations):
    """The observations with the rubric's report: :meth:`report` gives the grade."""

    def feed(self, topic: str, msg: msgs.Message | None, t_ns: int) -> None:
        """One message of the log, observed only when a TA would have seen it (within the
        time limit: :func:`seen_by_the_ta`); a run stopped in the recorder's grace after it
        scores nothing there."""
        if seen_by_the_ta(self, t_ns):
            super().feed(topic, msg, t_ns)

    def found_markers(self) -> tuple[FoundMarker, ...]:
        """The markers broadcast, as :func:`marker_broadcast` judges them, with the error of
        the frame the line shows."""
        out = []
        for mid in self.broadcasts:
            places = frame_places(self, mid)
            if not places:
                continue
            shown = shown_place(places)
            worst = shown.error_m if math.isfinite(shown.error_m) else None
            out.append(FoundMarker(mid, place_text(places, shown), worst))
        return tuple(out)

    def report(
        self, source: str, *, log_complete: bool = True, log_problem: str = ""
    ) -> GradeReport:
        """The rubric as judged from what was fed so far (a truncated log: as far as it goes)."""
        return GradeReport(
            source,
            judge(self),
            self.start_ns or 0,
            log_complete,
            log_problem,
            thresholds=self.resolved_thresholds(),
            scenario=self.scenario.name,
            rubric="usar",
            rubric_version=RUBRIC_VERSION,
        )


def judge(g: Observations) -> tuple[Check, ...]:
    """Every rubric line, in rubric order, from what ``g`` observed."""
    targets = explorer_targets(g)
    last_target = last_reached(
        [f"target_{k + 1}" for k in range(len(g.targets))], in_order(g.target_discs)
    )
    markers = follower_markers(g)
    home = follower_home(g)
    lines: list[Check] = [
        *targets,
        *(marker_detected(g, mid) for mid in g.markers),
        *(marker_broadcast(g, mid) for mid in g.markers),
        only_on_detection(g),
        explorer_home_before_follower(g, *last_target),
        *markers,
        home,
        time_limit(g, home.evidence_ns),
        *(one_cmd_vel_publisher(g, r) for r in contract.ROBOTS),
    ]
    return tuple(lines)


RUBRIC = Rubric(
    Grader,
    GRADE_TOPICS,
    REQUIRED_TOPICS,
    trusted_topics=(contract.FIDUCIALS,),
    version=RUBRIC_VERSION,
)
"""The US&R rubric, as its assignment carries it."""
