"""The one registry of rubrics: an assignment's name -> the factory of the rubric that grades it.

Why a registry here and not a field of the assignment: an assignment is a fact of the world
layer (:mod:`usar_replay.world.assignment`), which knows nothing of grading; grade, replay, the
batch and the HTML report ask this module for a run's rubric by its scenario's assignment. The
built-in rubrics are imported when first asked for (``usar info`` and the viewer never load
them). A package that adds an assignment registers its rubric with :func:`register_rubric` from
its ``usar_replay.assignments`` entry point (``docs/assignments.md``).
"""

from __future__ import annotations

from collections.abc import Callable

from usar_replay.core.errors import InvalidScenario
from usar_replay.grading.verdict import Rubric
from usar_replay.world.assignment import load_plugins
from usar_replay.world.scenario import Scenario

__all__ = ["RubricFactory", "register_rubric", "rubric_for", "rubric_of"]

RubricFactory = Callable[[], Rubric]
"""Makes the rubric (called each time one is asked for; cache inside it if it is costly)."""


def _usar() -> Rubric:
    from usar_replay.grading import usar

    return usar.RUBRIC


def _ros2_final() -> Rubric:
    from usar_replay.grading import rubric_ros2

    return rubric_ros2.RUBRIC


_RUBRICS: dict[str, RubricFactory] = {"usar": _usar, "ros2-final": _ros2_final}


def register_rubric(assignment: str, factory: RubricFactory) -> None:
    """Grade the assignment called ``assignment`` with the rubric ``factory()`` makes.
    Registering the same factory twice is harmless; another one under a taken name is a
    ValueError."""
    known = _RUBRICS.get(assignment)
    if known is not None and known is not factory:
        raise ValueError(f"assignment {assignment!r} already has a rubric")
    _RUBRICS[assignment] = factory


def rubric_of(assignment: str) -> Rubric:
    """The rubric of the assignment called ``assignment`` (:class:`InvalidScenario` when no
    rubric is registered for it, after loading the packages' entry points)."""
    factory = _RUBRICS.get(assignment)
    if factory is None:
        load_plugins()
        factory = _RUBRICS.get(assignment)
    if factory is None:
        raise InvalidScenario(f"assignment {assignment!r} has no rubric: it cannot be graded")
    return factory()


def rubric_for(scenario: Scenario) -> Rubric:
    """The rubric of the scenario's assignment."""
    return rubric_of(scenario.assignment)
