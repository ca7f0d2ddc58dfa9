"""`usar report`: a self-contained HTML page per run (map, rubric, detection frames), an index."""

from __future__ import annotations

import base64
import re
from html.parser import HTMLParser
from pathlib import Path

from usar_replay.cli.main import main
from usar_replay.core import contract, msgs
from usar_replay.grading.grade import grade_file
from usar_replay.log import bag
from usar_replay.pipeline.record import RecordResult


class _Page(HTMLParser):
    """The parts of a page a test checks: images, links, table cells, text."""

    def __init__(self) -> None:
        super().__init__()
        self.images: list[dict[str, str]] = []
        self.links: list[str] = []
        self.cells: list[str] = []
        self.text: list[str] = []
        self._in_cell = False
        self._svg = ""
        self.polygons: list[dict[str, str]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        if tag == "img":
            self.images.append(a)
        elif tag == "svg":
            self._svg = a.get("aria-label", "")
        elif tag == "image":  # a detection frame drawn in SVG, under the marker's outline
            self.images.append({"alt": self._svg, "src": a.get("href", "")})
        elif tag == "polygon":
            self.polygons.append({"svg": self._svg, **a})
        elif tag == "a":
            self.links.append(a.get("href", ""))
        elif tag == "td":
            self._in_cell = True
            self.cells.append("")
        if tag in ("script", "link", "iframe"):
            raise AssertionError(f"a self-contained page has no <{tag}>")

    def handle_endtag(self, tag: str) -> None:
        if tag == "td":
            self._in_cell = False

    def handle_data(self, data: str) -> None:
        self.text.append(data)
        if self._in_cell:
            self.cells[-1] += data


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8"))
    return page


def _first_detected_frame(log: Path) -> bytes:
    frames: dict[int, bytes] = {}
    for m in bag.BagReader(log).messages([contract.IMAGE, contract.FIDUCIALS]):
        if isinstance(m.msg, msgs.CompressedImage):
            frames[m.msg.header.stamp.ns] = m.msg.data
        elif isinstance(m.msg, msgs.FiducialTransformArray) and m.msg.transforms:
            return frames[m.msg.header.stamp.ns]
    raise AssertionError("no detection in the log")


def test_report_writes_a_self_contained_page_and_an_index(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    out = tmp_path / "pages"
    assert main(["report", str(room_log[0]), "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["index.html", "room.html"]

    page = _parse(out / "room.html")
    text = " ".join(page.text)
    assert "60 / 60" in text and "PASS" in text
    # every image is embedded: the map (PNG) and the detection frame (the recorded bytes)
    assert page.images and all(i["src"].startswith("data:image/") for i in page.images)
    assert page.links == []
    map_img = next(i for i in page.images if i["alt"] == "map of the run")
    png = base64.b64decode(map_img["src"].split(",", 1)[1])
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
    frame = next(i for i in page.images if i["alt"] == "marker 0 (frame)")
    # the outline over it, and (35 px wide in a 320 px frame) a zoomed inset
    assert [p["svg"] for p in page.polygons] == ["marker 0 (frame)", "marker 0 (zoom)"]
    assert base64.b64decode(frame["src"].split(",", 1)[1]) == _first_detected_frame(room_log[0])
    first_s = grade_file(room_log[0]).check("marker_0.detected").evidence_ns / 1e9
    assert f"marker 0: first detected at {first_s:.1f} s" in text
    # the rubric table: every line, numbered, with its evidence time
    for line_id in ("explorer.target_1", "marker_0.broadcast", "follower.home", "time_limit"):
        assert any(c.startswith(line_id) for c in page.cells), line_id
    reached_s = grade_file(room_log[0]).check("explorer.target_1").evidence_ns / 1e9
    assert any(re.fullmatch(rf"{reached_s:.1f} s \(reached\)", c) for c in page.cells)

    index = _parse(out / "index.html")
    assert index.links == ["room.html"]
    assert "1/1 recordings pass" in " ".join(index.text)
