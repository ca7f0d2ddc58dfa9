"""The rubric's wording of times, counts and places."""

from __future__ import annotations

from usar_replay.grading.usar.words import plural, point, sim_s


def test_the_words() -> None:
    assert sim_s(12_345_000_000) == "12.3 s"
    assert (plural(1, "frame"), plural(0, "frame"), plural(3, "frame")) == (
        "1 frame",
        "0 frames",
        "3 frames",
    )
    assert point((1.234, -0.5)) == "(1.23, -0.50)"
