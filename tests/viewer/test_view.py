"""`usar view`: the .rrd holds what the log holds, in the tf tree's shape, read back with rerun.

Every check reads the written ``.rrd`` with rerun's own reader (``rerun.chunk.RrdReader``) and
compares it with the ``.mcap`` read by :class:`usar_replay.log.bag.BagReader`. Nothing here opens a
window or blocks: views go to files, the web server test runs in a subprocess with a timeout.
"""

from __future__ import annotations

import math
import re
import resource
import signal
import socket
import subprocess
import sys
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from clitools import no_display, one_error_line, start_usar, usar

from usar_replay.cli.main import main
from usar_replay.core import msgs
from usar_replay.core.contract import IMAGE as CAMERA_TOPIC
from usar_replay.core.contract import SCENARIO_ATTACHMENT
from usar_replay.grading.grade import grade_file
from usar_replay.log import bag
from usar_replay.log.bag import BagReader
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import RecordResult
from usar_replay.viewer.scene import escape_path_part, frame_entity_path, frame_entity_paths
from usar_replay.viewer.view import ViewResult, view_run
from usar_replay.viewer.viewer_process import (
    Output,
    open_command,
)
from usar_replay.world.detect import DetectorParams, detect_with_corners

OPTICAL = (
    "/map/explorer_tf/odom/explorer_tf/base_footprint/explorer_tf/camera_rgb_frame"
    "/explorer_tf/camera_rgb_optical_frame"
)
PINHOLE = OPTICAL + "/pinhole"
IMAGE = PINHOLE + "/image"
DETECTIONS = PINHOLE + "/detections"
MARKER_FRAME = OPTICAL + "/marker_frame"
BASE = "/map/explorer_tf/odom/explorer_tf/base_footprint"


@dataclass
class Entity:
    """One entity of an .rrd: its static and temporal chunks as Arrow batches."""

    static: list[pa.RecordBatch] = field(default_factory=list)
    temporal: list[pa.RecordBatch] = field(default_factory=list)
    timelines: set[str] = field(default_factory=set)

    def rows(self, column: str) -> int:
        """Temporal rows that hold ``column`` (e.g. ``EncodedImage:blob``)."""
        return sum(
            b.num_rows - b.column(column).null_count
            for b in self.temporal
            if column in b.schema.names
        )

    def values(self, column: str) -> list[Any]:
        """The column's rows (each a list of instances) in time order."""
        out: list[Any] = []
        for b in sorted(self.temporal, key=lambda b: _first_time(b)):
            if column in b.schema.names:
                out += b.column(column).to_pylist()
        return out

    def times(self) -> list[int]:
        out: list[int] = []
        for b in self.temporal:
            out += [t.value for t in b.column(_index_name(b))]
        return sorted(out)

    def static_value(self, column: str) -> Any:
        for b in self.static:
            if column in b.schema.names:
                return b.column(column).to_pylist()[-1]
        raise KeyError(column)


def _index_name(batch: pa.RecordBatch) -> str:
    """The batch's time column (rerun marks it ``rerun:kind = index``)."""
    for f in batch.schema:
        if (f.metadata or {}).get(b"rerun:kind") == b"index":
            return str(f.name)
    raise KeyError("no index column")


def _first_time(batch: pa.RecordBatch) -> int:
    return int(batch.column(_index_name(batch))[0].value)


def read_rrd(path: Path) -> dict[str, Entity]:
    """Every entity of the first recording in ``path``, via rerun's chunk reader."""
    out: dict[str, Entity] = {}
    for chunk in rr.chunk.RrdReader(path).stream():
        e = out.setdefault(chunk.entity_path, Entity())
        batch = chunk.to_record_batch()
        (e.static if chunk.is_static else e.temporal).append(batch)
        e.timelines.update(chunk.timeline_names)
    return out


@dataclass
class Viewed:
    log: Path
    rrd: Path
    result: ViewResult
    entities: dict[str, Entity]
    reader: BagReader


@pytest.fixture(scope="module")
def viewed(room_log: tuple[Path, RecordResult], tmp_path_factory: pytest.TempPathFactory) -> Viewed:
    """The room mission written to an .rrd once (with the rubric), and read back."""
    log, _ = room_log
    rrd = tmp_path_factory.mktemp("view") / "room.rrd"
    result = view_run(open_run(log), Output(rrd=rrd), grade=True)
    return Viewed(log, rrd, result, read_rrd(rrd), BagReader(log))


def _messages(reader: BagReader, topic: str) -> Iterator[msgs.Message]:
    for m in reader.messages(topics=[topic]):
        assert m.msg is not None
        yield m.msg


# --- what the .rrd holds ------------------------------------------------------------------------


def test_every_camera_frame_is_an_image_row_with_the_recorded_bytes(viewed: Viewed) -> None:
    frames = viewed.reader.topics[CAMERA_TOPIC].count
    image = viewed.entities[IMAGE]
    assert frames > 100
    assert image.rows("EncodedImage:blob") == frames == viewed.result.frames
    first = next(_messages(viewed.reader, CAMERA_TOPIC))
    assert isinstance(first, msgs.CompressedImage)
    blob = bytes(image.values("EncodedImage:blob")[0][0])
    assert blob == first.data  # logged as recorded: JPEG bytes (the default), not decoded pixels
    assert image.values("EncodedImage:media_type")[0] == ["image/jpeg"]


@pytest.mark.parametrize("robot", ["explorer", "follower"])
def test_cmd_vel_plots_have_a_row_per_message(viewed: Viewed, robot: str) -> None:
    twists = list(_messages(viewed.reader, f"/{robot}/cmd_vel"))
    assert len(twists) > 50
    linear = viewed.entities[f"/plots/{robot}/cmd_vel/linear_x"]
    angular = viewed.entities[f"/plots/{robot}/cmd_vel/angular_z"]
    assert linear.rows("Scalars:scalars") == angular.rows("Scalars:scalars") == len(twists)
    got = [v[0] for v in angular.values("Scalars:scalars")]
    want = [t.angular.z for t in twists if isinstance(t, msgs.Twist)]
    assert got == pytest.approx(want)


def test_tf_tree_is_the_entity_tree(viewed: Viewed) -> None:
    """marker_frame sits under the optical frame, which sits under base_footprint, under map."""
    marker_tfs = [
        tf
        for m in _messages(viewed.reader, "/tf")
        if isinstance(m, msgs.TFMessage)
        for tf in m.transforms
        if tf.child_frame_id == "marker_frame"
    ]
    assert marker_tfs
    assert viewed.entities[MARKER_FRAME].rows("Transform3D:translation") == len(marker_tfs)
    base_rows = viewed.entities[BASE].rows("Transform3D:translation")
    assert base_rows == viewed.reader.topics["/ground_truth/explorer/pose"].count
    odom = viewed.entities["/map/explorer_tf/odom"]
    assert not odom.temporal
    translation = np.ravel(np.asarray(odom.static_value("Transform3D:translation")))
    # static, and the identity: odometry is world-source, as the course's Gazebo publishes it
    assert translation == pytest.approx([0.0, 0.0, 0.0])
    # the camera's static chain was logged as static, with the optical rotation
    optical = viewed.entities[OPTICAL]
    assert not optical.temporal and optical.static_value("Transform3D:quaternion") is not None


def test_one_timeline_named_sim_time_in_nanoseconds(viewed: Viewed) -> None:
    timelines = set().union(*(e.timelines for e in viewed.entities.values()))
    assert timelines == {"sim_time"}
    image = viewed.entities[IMAGE]
    assert image.temporal[0].schema.field("sim_time").type == pa.duration("ns")
    assert image.times()[0] == viewed.reader.start_ns  # sim time itself, not shifted


def test_blueprint_and_footer_are_written(viewed: Viewed) -> None:
    reader = rr.chunk.RrdReader(viewed.rrd)
    assert len(reader.blueprints()) == 1
    assert len(reader.store()) > 10  # LazyStore needs the footer: the file was finalised
    assert not viewed.rrd.with_name("room.rrd.part").exists()
    assert list(viewed.rrd.parent.iterdir()) == [viewed.rrd]  # no temporary file left


def test_pinhole_matches_the_camera_info(viewed: Viewed) -> None:
    info = next(_messages(viewed.reader, "/explorer/camera/rgb/camera_info"))
    assert isinstance(info, msgs.CameraInfo)
    pinhole = viewed.entities[PINHOLE]
    k = np.asarray(pinhole.static_value("Pinhole:image_from_camera"), dtype=np.float64)
    # rerun stores the 3x3 column-major
    np.testing.assert_allclose(k.reshape(3, 3).T, np.asarray(info.k).reshape(3, 3), rtol=1e-6)
    resolution = np.ravel(np.asarray(pinhole.static_value("Pinhole:resolution")))
    assert resolution == pytest.approx([info.width, info.height])


def test_detection_outlines_land_on_the_detected_corners(viewed: Viewed) -> None:
    """Projected outlines (from the recorded poses) agree with re-detected corners."""
    detections = viewed.entities[DETECTIONS]
    arrays = list(_messages(viewed.reader, "/fiducial_transforms"))
    assert detections.rows("LineStrips2D:strips") == len(arrays)  # a row per frame, even empty
    strips = detections.values("LineStrips2D:strips")
    n_published = sum(
        len(a.transforms) for a in arrays if isinstance(a, msgs.FiducialTransformArray)
    )
    assert sum(len(s or []) for s in strips) == n_published > 0
    # one frame, re-detected by the real detector
    info = next(_messages(viewed.reader, "/explorer/camera/rgb/camera_info"))
    assert isinstance(info, msgs.CameraInfo)
    times = detections.times()
    # the detector runs only while the explorer searches: frames and arrays pair by stamp
    images = {
        m.header.stamp.ns: m
        for m in _messages(viewed.reader, CAMERA_TOPIC)
        if isinstance(m, msgs.CompressedImage)
    }
    for i, array in enumerate(arrays):
        if isinstance(array, msgs.FiducialTransformArray) and array.transforms:
            image = images[array.header.stamp.ns]
            _, corners = detect_with_corners(image, info, DetectorParams())
            mid = array.transforms[0].fiducial_id
            drawn = np.asarray(strips[i][0], dtype=np.float64)[:4]
            assert drawn == pytest.approx(corners[mid], abs=1.5)
            assert times[i] == array.header.stamp.ns
            break
    else:
        pytest.fail("no frame with a detection")


def test_marker_frame_in_map_is_near_the_true_marker(viewed: Viewed) -> None:
    truth = next(_messages(viewed.reader, "/ground_truth/markers"))
    assert isinstance(truth, msgs.FiducialTransformArray)
    true_xyz = [
        (f.transform.translation.x, f.transform.translation.y, f.transform.translation.z)
        for f in truth.transforms
    ]
    layer = viewed.entities["/map/marker_frame_in_map"]
    last = layer.values("Points3D:positions")[-1]
    labels = layer.values("Points3D:labels")[-1]
    assert len(last) == viewed.entities[MARKER_FRAME].rows("Transform3D:translation")
    for p, label in zip(last, labels, strict=True):
        err = min(math.dist(p, t) for t in true_xyz)
        assert err < 0.1
        shown = float(re.search(r"([0-9.]+) cm off", label).group(1))  # type: ignore[union-attr]
        assert shown == pytest.approx(err * 100, abs=0.06)
    true_layer = viewed.entities["/map/ground_truth/markers"]
    assert true_layer.values("Points3D:positions")[0] == [pytest.approx(t) for t in true_xyz]


def test_goals_paths_and_targets(viewed: Viewed) -> None:
    for robot in ("explorer", "follower"):
        goals = viewed.entities[f"/map/{robot}/goal"]
        assert goals.rows("Arrows3D:origins") == viewed.reader.topics[f"/{robot}/goal"].count
        path = viewed.entities[f"/map/ground_truth/{robot}_path"]
        strips = path.values("LineStrips3D:strips")
        assert len(strips) >= 10 and len(strips[-1][0]) >= len(strips[0][0])  # it grows
    targets = viewed.entities["/map/targets"]
    assert targets.static_value("Points3D:labels") == ["target_1"]
    walls = viewed.entities["/map/world/walls"]
    assert len(walls.static_value("Boxes3D:half_sizes")) == 4


def test_rosout_and_rubric_lines_in_the_text_log(viewed: Viewed) -> None:
    logs = list(_messages(viewed.reader, "/rosout"))
    rosout = viewed.entities["/logs/rosout"]
    assert rosout.rows("TextLog:text") == len(logs)
    levels = {"10": "DEBUG", "20": "INFO", "30": "WARN", "40": "ERROR"}
    want = [levels[str(m.level)] for m in logs if isinstance(m, msgs.Log)]
    assert [row[0] for row in rosout.values("TextLog:level")] == want
    report = grade_file(viewed.log)
    grade = viewed.entities["/logs/grade"]
    texts = [str(row[0]) for row in grade.values("TextLog:text")]
    assert len(texts) == len(report.checks) + 1  # each line, then the total
    for check in report.checks:
        line = next(t for t in texts if f" {check.id}:" in t)
        assert line.startswith("PASS" if check.passed else "FAIL")
    assert {row[0] for row in grade.values("TextLog:level")} == {"INFO"}
    evidence = sorted(c.evidence_ns for c in report.checks if c.evidence_ns is not None)
    assert set(evidence) <= set(grade.times())


# --- the pieces ----------------------------------------------------------------------------------


def test_frame_entity_paths_follow_the_tree_and_sanitise() -> None:
    parents = {"b/c": "a", "d e": "b/c", "/x": "d e", "loop1": "loop2", "loop2": "loop1"}
    paths = frame_entity_paths(parents)
    assert paths["a"] == "/a"
    assert paths["b/c"] == "/a/b/c"
    assert paths["d e"] == "/a/b/c/d\\ e"
    assert paths["/x"] == "/a/b/c/d\\ e/x"
    assert paths["loop1"].count("loop") <= 2  # a cycle is cut, not followed forever
    assert frame_entity_path({}, "camera") == "/camera"


def test_escape_path_part_is_rerun_own_escaping() -> None:
    """The pure part escapes frame ids without rerun; it must agree with rerun's function."""
    chars = [chr(c) for c in range(0, 0x180)] + ["日", "\u00a0", "\u2028", "😀", "ß"]
    for c in chars:
        assert escape_path_part(c) == rr.escape_entity_path_part(c), repr(c)
    for frame in ("explorer_tf/odom", "cam 1:left$", "a.b-c_d", "../x"):
        assert escape_path_part(frame) == rr.escape_entity_path_part(frame)


# --- rerun's own MCAP loader --------------------------------------------------------------------


def test_the_mcap_opens_in_rerun_own_mcap_loader(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """`rerun mcap convert` decodes our ROS 2 schemas: images, tf, logs, not just raw bytes."""
    log, _ = room_log
    out = tmp_path / "converted.rrd"
    done = subprocess.run(
        [sys.executable, "-m", "rerun_cli", "mcap", "convert", str(log), "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    entities = read_rrd(out)
    reader = BagReader(log)
    image = entities[CAMERA_TOPIC]
    assert image.rows("EncodedImage:blob") == reader.topics[CAMERA_TOPIC].count
    assert bytes(image.values("EncodedImage:blob")[0][0])[:2] == b"\xff\xd8"  # format "jpeg"
    children = {c for row in entities["/tf"].values("Transform3D:child_frame") for c in row}
    assert {"explorer_tf/base_footprint", "marker_frame"} <= children
    parents = {p for row in entities["/tf_static"].values("Transform3D:parent_frame") for p in row}
    parents |= {p for b in entities["/tf_static"].static for p in _flat(b, "parent_frame")}
    assert "map" in parents
    assert entities["/rosout"].rows("TextLog:text") == reader.topics["/rosout"].count


def _flat(batch: pa.RecordBatch, suffix: str) -> list[str]:
    names = [n for n in batch.schema.names if n.endswith(suffix)]
    return [v for n in names for row in batch.column(n).to_pylist() if row for v in row]


# --- the command ---------------------------------------------------------------------------------


def test_cli_save_prints_the_command_that_opens_it(
    room_log: tuple[Path, RecordResult], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log, _ = room_log
    out = tmp_path / "sub" / "view.rrd"
    assert main(["view", str(log), "--save", str(out)]) == 0
    stdout, stderr = capsys.readouterr()
    assert stdout.strip().splitlines()[-1] == open_command(out)
    assert open_command(out).split()[-1] == str(out) and "rerun" in open_command(out)
    assert stderr == ""
    assert read_rrd(out)[IMAGE].rows("EncodedImage:blob") > 0


def test_cli_without_display_writes_next_to_the_log(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    log = tmp_path / "copy.mcap"
    log.write_bytes(room_log[0].read_bytes())
    done = usar("view", str(log), env=no_display())
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "copy.rrd").exists()
    assert done.stdout.strip().splitlines()[-1].endswith(str(tmp_path / "copy.rrd"))


def test_cli_truncated_log_writes_what_it_read_and_exits_3(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    data = room_log[0].read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) * 6 // 10])
    out = tmp_path / "cut.rrd"
    done = usar("view", str(cut), "--save", str(out), env=no_display())
    assert done.returncode == 3
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"usar: {cut}: the log is incomplete")
    assert "sim time" in lines[0]  # says how far it got
    assert "Traceback" not in done.stderr
    frames = read_rrd(out)[IMAGE].rows("EncodedImage:blob")
    assert 0 < frames < BagReader(room_log[0]).topics[CAMERA_TOPIC].count
    note = read_rrd(out)["/logs/view"].values("TextLog:text")
    assert "incomplete" in str(note[0])


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_cli_web_serves_until_ctrl_c(room_log: tuple[Path, RecordResult]) -> None:
    web, grpc = _free_port(), _free_port()
    args = ["view", str(room_log[0]), "--web", "--web-port", str(web), "--grpc-port", str(grpc)]
    proc = start_usar(*args, env=no_display())
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        m = re.search(r"http://localhost:(\d+)/\?url=\S+", line)
        assert m and int(m.group(1)) == web, line
        with urllib.request.urlopen(m.group(0), timeout=20) as page:
            assert page.status == 200 and b"<html" in page.read().lower()
        assert proc.poll() is None  # still serving
        # the page and its data port listen on the same address (--bind, 127.0.0.1 by default)
        assert _listening_on(web) == _listening_on(grpc) == {"127.0.0.1"}
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
        assert proc.returncode == 130
        assert err.strip() == "usar: interrupted"
        assert _listening_on(web) == _listening_on(grpc) == set()  # its server stopped too
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def _listening_on(port: int) -> set[str]:
    """The IPv4 addresses a TCP socket listens on at ``port`` (from /proc/net/tcp)."""
    out: set[str] = set()
    for line in Path("/proc/net/tcp").read_text().splitlines()[1:]:
        local, state = line.split()[1], line.split()[3]
        addr, hex_port = local.split(":")
        if state == "0A" and int(hex_port, 16) == port:
            out.add(socket.inet_ntoa(bytes.fromhex(addr)[::-1]))
    return out


# --- outputs are never lost or left half-written (issue 13) --------------------------------------


def test_cli_existing_output_needs_overwrite(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    out = tmp_path / "old.rrd"
    out.write_bytes(b"old view")
    done = usar("view", str(room_log[0]), "--save", str(out))
    one_error_line(done, 2, str(out), "exists", "--overwrite")
    assert out.read_bytes() == b"old view"
    done = usar("view", str(room_log[0]), "--save", str(out), "--overwrite")
    assert done.returncode == 0, done.stderr
    assert read_rrd(out)[IMAGE].rows("EncodedImage:blob") > 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.rrd"]


def _limit_file_size() -> None:
    """In the child: files may not grow past 200 kB (what a full disk does to a writer)."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, 200_000))


def test_cli_a_failed_write_leaves_nothing(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    out = tmp_path / "big.rrd"
    done = subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", "view", str(room_log[0]), "--save", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        preexec_fn=_limit_file_size,  # only sets a limit: safe before exec
    )
    one_error_line(done, 2, str(out), "File too large")
    assert list(tmp_path.iterdir()) == []  # no .rrd, no 0-byte or partial temporary file


def test_cli_invalid_scenario_attachment_is_shown_without_the_building_exit_3(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    src = BagReader(room_log[0])
    bad = tmp_path / "bad.mcap"
    with bag.BagWriter(bad) as w:
        w.add_attachment(SCENARIO_ATTACHMENT, "application/toml", b"walls = 3", src.start_ns)
        for m in src.messages(decode_messages=False):
            w.write_raw(m.topic, m.msgtype, m.data, m.log_time_ns)
    out = tmp_path / "bad.rrd"
    done = usar("view", str(bad), "--save", str(out))
    assert done.returncode == 3, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "scenario is invalid" in lines[0] and "Traceback" not in lines[0]
    entities = read_rrd(out)
    assert entities[IMAGE].rows("EncodedImage:blob") == src.topics[CAMERA_TOPIC].count
    assert "/map/world/walls" not in entities
    assert "scenario is invalid" in str(entities["/logs/view"].values("TextLog:text")[0])


def test_cli_unusable_display_falls_back_to_a_file(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """DISPLAY names no X server: the viewer exits at once and the view goes to a file."""
    if Path("/tmp/.X11-unix/X99").exists():
        pytest.skip("display :99 exists here")
    log = tmp_path / "shown.mcap"
    log.write_bytes(room_log[0].read_bytes())
    env = {**no_display(), "DISPLAY": ":99"}
    done = usar("view", str(log), "--grpc-port", str(_free_port()), env=env)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("usar: the rerun viewer did not start")
    assert lines[0].endswith("wrote the view to a file")
    assert done.stdout.strip().splitlines()[-1].endswith(str(tmp_path / "shown.rrd"))
    assert read_rrd(tmp_path / "shown.rrd")[IMAGE].rows("EncodedImage:blob") > 0
