"""What the rubric keeps while it observes: arrivals only on stops where a line asks for one,
the follower's stops, and memory that stays flat on a hostile log."""

from __future__ import annotations

from rubric_streams import FOLLOWER_HOME, MARKERS, S, camera, detect, drive, send, world

from usar_replay.core import contract
from usar_replay.grading.usar import MAX_FRAMES, MAX_SAMPLES, Disc, Grader


def test_an_arrival_counts_only_where_it_may() -> None:
    """``counts`` False (moving): inside the disc is no arrival; the first stop inside is one,
    moving on inside it stays the same visit, and only leaving past ``leave`` re-arms it."""
    d = Disc((0.0, 0.0), 0.5, 0.55, True)
    d.update((0.2, 0.0), 1 * S, counts=False)  # driving through
    assert d.entries == []
    d.update((0.3, 0.0), 2 * S, counts=True)  # stopped inside: a visit
    d.update((0.1, 0.0), 3 * S, counts=False)  # moving inside: the same visit
    assert d.entries == [2 * S] and d.stay_closest == [0.1]
    d.update((0.52, 0.0), 4 * S, counts=False)  # on the edge: not left
    d.update((0.2, 0.0), 5 * S, counts=True)
    assert d.entries == [2 * S]
    d.update((1.0, 0.0), 6 * S, counts=False)  # left
    d.update((0.2, 0.0), 7 * S, counts=True)
    assert d.entries == [2 * S, 7 * S]


def test_a_stop_lasts_stopped_s_and_a_turn_in_place_is_one() -> None:
    g = Grader(world())
    drive(g, "follower", [FOLLOWER_HOME], S)
    assert g.follower_stops == 0  # one sample: not yet a stop
    drive(g, "follower", [FOLLOWER_HOME], 2 * S)  # the same place 1 s later (>= 0.5 s)
    assert g.follower_stops == 1
    drive(g, "follower", [(0.02, -1.0)], 3 * S)  # within 3 cm: still stopped
    drive(g, "follower", [(0.5, -1.0)], 4 * S)  # moved half a metre
    assert g.follower_stops == 2


def test_memory_stays_flat_on_a_flood_of_frames_and_broadcasts() -> None:
    """A new frame name every message, and thousands of broadcasts of one frame: the names
    past MAX_FRAMES share one entry, a frame keeps at most MAX_SAMPLES places."""
    g = Grader(world())
    camera(g, 5 * S)
    camera(g, 6 * S)  # the camera's place between its two transforms: every stamp looks up
    detect(g, [0], 5 * S)
    for k in range(MAX_FRAMES + 10):
        send(g, f"frame_{k}", MARKERS[0], 5 * S)
    assert len(g.broadcast_frames) == MAX_FRAMES + 1
    for k in range(MAX_SAMPLES + 50):
        t = 5 * S + k * 1000  # a new stamp each time
        send(g, "flood", MARKERS[0], t)
    flood = g.broadcasts[0].frames["(other frames)"]
    assert len(flood.elsewhere) <= MAX_SAMPLES and flood.elsewhere_count > MAX_SAMPLES
    assert contract.MARKER_FRAME not in g.broadcasts[0].frames
