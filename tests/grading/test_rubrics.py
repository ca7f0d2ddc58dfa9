"""grading/rubrics: the registry that finds an assignment's rubric."""

from __future__ import annotations

import dataclasses

import pytest

from usar_replay.core import contract
from usar_replay.core.errors import InvalidScenario
from usar_replay.grading import rubric_ros2, rubrics, usar
from usar_replay.grading.verdict import Rubric
from usar_replay.world.scenario import course_world


def test_the_built_in_assignments_have_their_rubrics() -> None:
    assert rubrics.rubric_of("usar") is usar.RUBRIC
    assert rubrics.rubric_of("ros2-final") is rubric_ros2.RUBRIC
    assert rubrics.rubric_for(course_world()) is usar.RUBRIC


def test_an_unknown_assignment_cannot_be_graded() -> None:
    with pytest.raises(InvalidScenario, match="assignment 'no-such-course' has no rubric"):
        rubrics.rubric_of("no-such-course")


def test_a_registered_rubric_is_found_and_a_second_one_refused() -> None:
    toy = dataclasses.replace(usar.RUBRIC, required_topics=(contract.ROSOUT,))

    def factory() -> Rubric:
        return toy

    name = "toy-assignment-for-test-rubrics"
    try:
        rubrics.register_rubric(name, factory)
        rubrics.register_rubric(name, factory)  # the same factory again: harmless
        assert rubrics.rubric_of(name) is toy
        with pytest.raises(ValueError, match="already has a rubric"):
            rubrics.register_rubric(name, lambda: toy)
        with pytest.raises(ValueError, match="'usar' already has a rubric"):
            rubrics.register_rubric("usar", factory)
    finally:
        rubrics._RUBRICS.pop(name, None)
    assert rubrics.rubric_of("usar") is usar.RUBRIC
