"""ros1/layout: fixed in-sandbox paths for the built workspaces (the end-to-end check that a log
does not depend on where the build is kept: tests/ros1/test_record.py)."""

from __future__ import annotations

from pathlib import Path

from usar_replay.ros1.building import layout


def test_each_underlay_has_its_own_fixed_read_only_place() -> None:
    host = [Path("/cache/a/ws"), Path("/cache/b/ws")]
    assert layout.mounts(host) == (
        ("/cache/a/ws", layout.UNDERLAY),
        ("/cache/b/ws", layout.UNDERLAY + "2"),
    )
    assert layout.underlay_at(0) == layout.UNDERLAY


def test_the_fixed_places_do_not_overlap_and_name_the_layout() -> None:
    places = [layout.WORKSPACE, *(layout.underlay_at(i) for i in range(3))]
    assert len(set(places)) == len(places)
    assert all(p.startswith("/ros1/") and Path(p).is_absolute() for p in places)
    assert not any(a != b and b.startswith(a + "/") for a in places for b in places)
    assert layout.VERSION != layout.HOST  # a host-path build never reuses a fixed one
