"""The grader can fail: faulty logs fail exactly the rubric line they break, and no other.

Faults that need several markers or targets are synthetic course-world missions
(:func:`logtools.synthetic_mission`, passing every line by default); the rest are edited copies
of the real recorded one-room log (fixture ``room_log``). Each test names the exact
``Check.id`` that must fail and asserts that every other line passes.
"""

from __future__ import annotations

import csv
import io
import json
import math
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import pytest
from clitools import one_error_line, usar
from logtools import SyntheticRun, rewrite, synthetic_mission, truncate_at

from usar_replay.cli.main import main
from usar_replay.core import msgs
from usar_replay.core.errors import MissingTopic, UsageError
from usar_replay.grading.grade import GradeReport, Thresholds, grade_file, load_thresholds
from usar_replay.grading.usar import MAX_VISITS, NO_DETECTOR, Grader
from usar_replay.log import bag
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import RecordResult
from usar_replay.world.scenario import course_world

COURSE_LINES = 22  # 4 targets, 4 x (detected, broadcast), only_on_detection, home, 4 follower,
# 2 more, and one cmd_vel line per robot
ROOM_LINES = 10  # + one cmd_vel line per robot


# --- synthetic course-world missions ------------------------------------------------------------


def test_a_clean_synthetic_mission_passes_every_line(tmp_path: Path) -> None:
    """The baseline the fault tests depend on: nothing fails when nothing is wrong."""
    path = tmp_path / "ok.mcap"
    synthetic_mission(path, course_world())
    report = grade_file(path)
    assert len(report.checks) == COURSE_LINES
    assert report.failed_ids() == []
    assert report.points == pytest.approx(60.0) and report.max_points == pytest.approx(60.0)
    assert report.log_complete


@pytest.mark.parametrize(
    ("fault", "kwargs", "failing"),
    [
        (
            "follower visits marker 1 before marker 0",
            {"follower_route": [1, 0, 2, 3, (-1.0, 2.5)]},
            ["follower.marker_1"],
        ),
        (
            "follower skips marker 2",
            {"follower_route": [0, 1, 3, (-1.0, 2.5)]},
            ["follower.marker_2"],
        ),
        ("explorer skips target_2", {"explorer_route": [1, 3, 4]}, ["explorer.target_2"]),
        (
            "explorer visits target_2 before target_1",
            {"explorer_route": [2, 1, 3, 4]},
            ["explorer.target_2"],
        ),
        (
            "explorer passes home mid-mission but never returns at the end",
            {"explorer_route": [1, 2, (-4.0, 2.5), 3, 4], "explorer_returns": False},
            ["explorer.home_before_follower"],
        ),
        (
            "follower moves while the explorer is still out",
            {"follower_wiggle_after_stop": 2},
            ["explorer.home_before_follower"],
        ),
        (  # and only_on_detection has nothing to judge: no credit without a broadcast
            "marker_frame never broadcast",
            {"broadcast": False},
            [*(f"marker_{k}.broadcast" for k in range(4)), "marker_frame.only_on_detection"],
        ),
    ],
)
def test_a_fault_fails_exactly_its_line(
    tmp_path: Path, fault: str, kwargs: dict[str, object], failing: list[str]
) -> None:
    path = tmp_path / "faulty.mcap"
    synthetic_mission(path, course_world(), **kwargs)  # type: ignore[arg-type]
    report = grade_file(path)
    assert report.failed_ids() == failing, fault
    assert len(report.checks) == COURSE_LINES


def test_out_of_order_is_said_in_the_measured_value(tmp_path: Path) -> None:
    path = tmp_path / "faulty.mcap"
    synthetic_mission(path, course_world(), follower_route=[1, 0, 2, 3, (-1.0, 2.5)])
    line = grade_file(path).check("follower.marker_1")
    assert "out of ID order" in line.measured and line.points == 0
    assert line.evidence_ns is not None  # where it came closest: something to look at


def test_driving_past_a_later_target_first_is_not_out_of_order(tmp_path: Path) -> None:
    """Order is a subsequence of arrivals: crossing target_3 on the way to target_1 is fine."""
    path = tmp_path / "ok.mcap"
    t3 = course_world().targets[2]
    synthetic_mission(path, course_world(), explorer_route=[(t3[0], t3[1]), 1, 2, 3, 4])
    assert grade_file(path).failed_ids() == []


def test_a_broadcast_with_another_parent_fails_only_on_detection(tmp_path: Path) -> None:
    """A marker_frame whose parent is not the camera optical frame (here ``map``, which in the
    synthetic world is the same place, so its position is still right)."""
    src, path = tmp_path / "ok.mcap", tmp_path / "faulty.mcap"
    synthetic_mission(src, course_world())
    changed = 0

    def edit(m: bag.BagMessage) -> msgs.Message | None:
        nonlocal changed
        if m.topic == "/tf" and isinstance(m.msg, msgs.TFMessage) and not changed:
            tf = m.msg.transforms[0]
            if tf.child_frame_id == "marker_frame":
                changed += 1
                header = replace(tf.header, frame_id="map")
                return msgs.TFMessage(transforms=(replace(tf, header=header),))
        return None

    rewrite(src, path, edit)
    assert changed == 1
    report = grade_file(path)
    assert report.failed_ids() == ["marker_frame.only_on_detection"]
    assert "1 with another parent" in report.check("marker_frame.only_on_detection").measured


# --- edited copies of the real recorded log -------------------------------------------------------


def test_the_real_log_passes_every_line(room_log: tuple[Path, RecordResult]) -> None:
    report = grade_file(room_log[0])
    assert len(report.checks) == ROOM_LINES
    assert report.failed_ids() == [] and report.points == 60
    broadcast = report.check("marker_0.broadcast")
    assert "cm from the marker" in broadcast.measured and broadcast.evidence_ns is not None


def test_marker_frame_never_broadcast(room_log: tuple[Path, RecordResult], tmp_path: Path) -> None:
    path = tmp_path / "no_marker_frame.mcap"
    dropped = 0

    def edit(m: bag.BagMessage) -> bool | None:
        nonlocal dropped
        if isinstance(m.msg, msgs.TFMessage) and any(
            t.child_frame_id == "marker_frame" for t in m.msg.transforms
        ):
            dropped += 1
            return False
        return None

    rewrite(room_log[0], path, edit)
    assert dropped >= 1
    report = grade_file(path)
    # no broadcast at all: only_on_detection has nothing to judge and gives no credit
    assert report.failed_ids() == ["marker_0.broadcast", "marker_frame.only_on_detection"]
    assert report.check("marker_0.broadcast").measured == "nothing broadcast on /tf"
    assert report.check("marker_frame.only_on_detection").measured.startswith("nothing broadcast")


def test_a_log_without_the_detector_is_graded_not_refused(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """A complete log with no /fiducial_transforms at all (a mission that did not start
    ArucoDetect) is a graded run: `usar grade` exits 1, not 3, and the table says why the
    detection line failed; exit 3 stays for damaged logs."""
    path = tmp_path / "no_detector.mcap"
    rewrite(room_log[0], path, lambda m: False if m.topic == "/fiducial_transforms" else None)
    assert "/fiducial_transforms" not in open_run(path).topics
    report = grade_file(path)
    assert report.log_complete
    line = report.check("marker_0.detected")
    assert not line.passed and line.measured == NO_DETECTOR
    assert report.check("explorer.target_1").passed  # the robots' lines are judged as usual
    out = usar("grade", str(path))
    assert out.returncode == 1, out.stderr
    assert "Traceback" not in out.stderr and "missing" not in out.stderr
    table = " ".join(out.stdout.split())  # the table wraps its measured column
    assert "FAIL 0/12 marker_0.detected " + NO_DETECTOR in table, out.stdout


def test_a_broadcast_20_cm_off_fails_the_broadcast_line(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """Every broadcast of marker_frame 20 cm off along the image's x: the frame a TA sees is
    off, the line fails with its worst broadcast as evidence. One wild broadcast among right
    ones does not move the frame's median (the line passes)."""
    assert _moved(room_log[0], tmp_path / "one.mcap", every=False).failed_ids() == []
    path = tmp_path / "moved.mcap"
    report = _moved(room_log[0], path, every=True)
    assert report.failed_ids() == ["marker_0.broadcast"]
    line = report.check("marker_0.broadcast")
    worst_cm = float(line.measured.split(", ")[1].split(" cm")[0])
    assert 15.0 < worst_cm < 25.0
    assert line.evidence.startswith("worst broadcast: marker_frame stamped")


def _moved(src: Path, path: Path, *, every: bool) -> GradeReport:
    """``src`` with the first (or every) marker_frame broadcast 0.2 m off, graded."""
    moved_at: list[int] = []

    def edit(m: bag.BagMessage) -> msgs.Message | None:
        if m.topic == "/tf" and isinstance(m.msg, msgs.TFMessage) and (every or not moved_at):
            tf = m.msg.transforms[0]
            if tf.child_frame_id == "marker_frame":
                moved_at.append(m.log_time_ns)
                v = tf.transform.translation
                shifted = replace(tf.transform, translation=replace(v, x=v.x + 0.2))
                return msgs.TFMessage(transforms=(replace(tf, transform=shifted),))
        return None

    rewrite(src, path, edit)
    assert moved_at
    return grade_file(path)


def test_a_broadcast_on_a_frame_without_detection(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """Empty the detections of the last broadcast's frame and of the frame before it (one
    camera period, 0.1 s, earlier): each broadcast of those frames came right after an empty
    detection, and is no copy of a recent one (the camera turned since)."""
    path = tmp_path / "undetected.mcap"
    stamps = [
        t.header.stamp.ns
        for m in bag.BagReader(room_log[0]).messages(["/tf"])
        if isinstance(m.msg, msgs.TFMessage)
        for t in m.msg.transforms
        if t.child_frame_id == "marker_frame"
    ]

    def edit(m: bag.BagMessage) -> msgs.Message | None:
        msg = m.msg
        if (
            isinstance(msg, msgs.FiducialTransformArray)
            and 0 <= stamps[-1] - msg.header.stamp.ns <= 100_000_000
        ):
            return replace(msg, transforms=())
        return None

    rewrite(room_log[0], path, edit)
    report = grade_file(path)
    assert report.failed_ids() == ["marker_frame.only_on_detection"]
    line = report.check("marker_frame.only_on_detection")
    emptied = [s for s in stamps if 0 <= stamps[-1] - s <= 100_000_000]
    assert f", {len(emptied)} without a detection within 2 s" in line.measured, line.measured
    assert line.evidence_ns == emptied[0]


def test_a_run_longer_than_10_minutes_fails_the_time_limit(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """The course's 600 s limit, and a 10-minute pause after the explorer is home: what the
    follower does after the limit is not seen (issue 51), so its lines fail with it."""
    src = room_log[0]
    scenario = replace(open_run(src).require_scenario(), time_limit_s=600.0)
    before = grade_file(src)
    home = before.check("explorer.home_before_follower").evidence_ns
    assert home is not None
    pause_after = home + 1_000_000_000
    path = tmp_path / "slow.mcap"
    rewrite(
        src,
        path,
        scenario=scenario,
        retime=lambda t: t if t <= pause_after else t + 600_000_000_000,
    )
    report = grade_file(path)
    assert report.failed_ids() == ["follower.marker_0", "follower.home", "time_limit"]
    line = report.check("time_limit")
    assert line.measured == "not completed (follower not home within 600 s)"
    assert line.threshold == "<= 600 s"
    assert before.points - report.points == sum(
        c.points for c in before.checks if c.id in report.failed_ids()
    )


def test_thresholds_from_toml_change_the_verdict(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    toml = tmp_path / "ta.toml"
    toml.write_text("[thresholds]\ntime_limit_s = 30\nfollower_visit_m = 0.1\n")
    th = load_thresholds(toml)
    assert th == Thresholds(time_limit_s=30.0, follower_visit_m=0.1)
    report = grade_file(room_log[0], th)
    # the visit's radius shrinks below the follower's stop; home after 30 s is not seen
    assert report.failed_ids() == ["follower.marker_0", "follower.home", "time_limit"]
    assert report.check("time_limit").threshold == "<= 30 s"


def test_a_truncated_log_is_graded_as_far_as_it_goes(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """Cut after the marker was stored but before the follower is home: what happened before
    the cut passes, what did not happen yet fails, and the report says the log is incomplete."""
    src = room_log[0]
    full = grade_file(src)
    broadcast = full.check("marker_0.broadcast").evidence_ns
    follower_home = full.check("follower.home").evidence_ns
    assert broadcast is not None and follower_home is not None
    path = tmp_path / "cut.mcap"
    last = truncate_at(src, path, broadcast + 2_000_000_000)
    assert last < follower_home
    report = grade_file(path)
    assert not report.log_complete and "truncated" in report.log_problem
    passed = {c.id for c in report.checks if c.passed}
    assert {"explorer.target_1", "marker_0.detected", "marker_0.broadcast"} <= passed
    assert {"follower.home", "time_limit"} <= set(report.failed_ids())

    out = usar("grade", str(path))
    assert out.returncode == 3
    assert "Traceback" not in out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "incomplete" in lines[0] and "as far as it goes" in lines[0]
    assert "PASS" in out.stdout and "explorer.target_1" in out.stdout


# --- the grader's own state stays bounded ---------------------------------------------------------


def test_grader_memory_does_not_grow_with_the_log() -> None:
    """Detections are remembered for ``detection_recent_s`` only; visits are capped."""
    g = Grader(course_world())
    tx, ty = course_world().targets[0]
    t = 1_000_000_000
    for i in range(5000):  # 500 s of 10 Hz detections, and an explorer bouncing on a target
        t += 100_000_000
        stamp = msgs.Time.from_ns(t)
        g.feed(
            "/fiducial_transforms",
            msgs.FiducialTransformArray(
                header=msgs.Header(stamp=stamp),
                transforms=(msgs.FiducialTransform(fiducial_id=0),),
            ),
            t,
        )
        off = 0.0 if i % 2 else 1.0
        pose = msgs.Pose(position=msgs.Point(x=tx + off, y=ty))
        g.feed("/ground_truth/explorer/pose", msgs.PoseStamped(pose=pose), t)
    assert len(g._detections) <= g.recent_ns // 100_000_000 + 1
    assert len(g.target_discs[0].entries) == MAX_VISITS
    assert g.target_discs[0].entries[-1] == t  # the newest arrival is kept


# --- thresholds ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("[thresholds]\nhome_m = -1\n", "out of range"),
        ("[thresholds]\nhome_m = true\n", "expected a number"),
        ("[thresholds]\nhome_meters = 0.2\n", "unknown setting"),
        ("[thresholds\nhome_m = 0.2\n", "invalid TOML"),
        ("home_m = 0.2\n", "[thresholds] table"),
    ],
)
def test_bad_thresholds_are_usage_errors(tmp_path: Path, text: str, needle: str) -> None:
    toml = tmp_path / "bad.toml"
    toml.write_text(text)
    with pytest.raises(UsageError, match=r".*") as err:
        load_thresholds(toml)
    assert needle in str(err.value) and str(toml) in str(err.value)


def test_thresholds_defaults_are_the_course_values() -> None:
    th = Thresholds()
    assert th.follower_visit_m == 0.4 and th.time_limit_s is None
    assert all(
        v is None or (isinstance(v, float) and math.isfinite(v) and v > 0)
        for v in (getattr(th, f) for f in th.__dataclass_fields__)
    )


# --- the command ---------------------------------------------------------------------------------


def test_grade_exit_codes_and_outputs(room_log: tuple[Path, RecordResult], tmp_path: Path) -> None:
    """0 when every line passes, 1 when one fails; JSON, JUnit (a case per line per recording),
    CSV (a row per recording), the same with --jobs 2; a bad file is reported, not dropped."""
    runs = tmp_path / "runs"
    runs.mkdir()
    good = runs / "a_good.mcap"
    good.write_bytes(room_log[0].read_bytes())
    bad_order = runs / "b_order.mcap"
    synthetic_mission(bad_order, course_world(), follower_route=[1, 0, 2, 3, (-1.0, 2.5)])
    assert main(["grade", str(good)]) == 0
    assert main(["grade", str(bad_order)]) == 1

    results: dict[int, str] = {}
    for jobs in (1, 2):
        j, x, c = tmp_path / f"g{jobs}.json", tmp_path / f"g{jobs}.xml", tmp_path / f"g{jobs}.csv"
        code = main(
            [
                *("grade", str(runs), "--jobs", str(jobs)),
                *("--json", str(j), "--junit", str(x), "--csv", str(c)),
            ]
        )
        assert code == 1
        results[jobs] = j.read_text()
    assert results[1] == results[2]
    data = json.loads(results[1])["recordings"]
    assert [d["source"] for d in data] == [str(good), str(bad_order)]
    assert [d["passed"] for d in data] == [True, False]
    failed = [c["id"] for c in data[1]["checks"] if not c["passed"]]
    assert failed == ["follower.marker_1"]
    suites = ET.parse(tmp_path / "g1.xml").getroot().findall("testsuite")
    assert [len(s.findall("testcase")) for s in suites] == [ROOM_LINES, COURSE_LINES]
    failing_cases = [tc.get("name") for tc in suites[1] if tc.find("failure") is not None]
    assert failing_cases == ["follower.marker_1"] and suites[1].get("failures") == "1"
    rows = list(csv.DictReader(io.StringIO((tmp_path / "g1.csv").read_text())))
    assert len(rows) == 2 and rows[1]["follower.marker_1"] == "fail"
    assert rows[0]["passed"] == "1" and rows[1]["passed"] == "0"


def test_a_bad_file_among_good_ones_is_one_line_and_still_reported(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    bad = tmp_path / "notes.mcap"
    bad.write_text("not a log")
    junit = tmp_path / "out.xml"
    out = usar("grade", str(room_log[0]), str(bad), "--junit", str(junit))
    one_error_line(out, 3, str(bad), "not an MCAP")
    assert "Grade of" in out.stdout and "1/2 recordings pass" in out.stdout
    names = [s.get("name") for s in ET.parse(junit).getroot().findall("testsuite")]
    assert names == [str(room_log[0]), str(bad)]


def test_grade_bad_inputs_are_one_line(room_log: tuple[Path, RecordResult], tmp_path: Path) -> None:
    no_scenario = tmp_path / "no_scenario.mcap"
    rewrite(room_log[0], no_scenario, keep_scenario=False)
    one_error_line(usar("grade", str(no_scenario)), 3, "scenario.toml")
    no_truth = tmp_path / "no_truth.mcap"
    rewrite(room_log[0], no_truth, lambda m: False if "/ground_truth/" in m.topic else None)
    with pytest.raises(MissingTopic):
        grade_file(no_truth)
    one_error_line(usar("grade", str(no_truth)), 3, "/ground_truth/explorer/pose", "missing")
    cut = tmp_path / "header_only.mcap"
    cut.write_bytes(room_log[0].read_bytes()[:20])
    out = usar("grade", str(cut))
    assert out.returncode == 3 and "Traceback" not in out.stderr
    bad_toml = tmp_path / "t.toml"
    bad_toml.write_text("[thresholds]\nnope = 1\n")
    one_error_line(usar("grade", str(room_log[0]), "--thresholds", str(bad_toml)), 2, "nope")
    one_error_line(usar("grade", str(room_log[0]), "--jobs", "0"), 2, "--jobs")
    empty = tmp_path / "empty_dir"
    empty.mkdir()
    one_error_line(usar("grade", str(empty)), 2, "no .mcap files")


def test_report_lookup_helpers() -> None:
    report = GradeReport("x", (), 0)
    assert report.passed and report.failed_ids() == []
    with pytest.raises(KeyError):
        report.check("time_limit")


def test_synthetic_run_writes_what_the_grader_needs(tmp_path: Path) -> None:
    """The synthetic builder itself: ground truth for both robots, /tf and detections."""
    path = tmp_path / "tiny.mcap"
    run = SyntheticRun(path, course_world())
    run.drive("explorer", (-3.0, 2.5))
    run.detect([0])
    run.close()
    topics = bag.BagReader(path).topics
    for t in ("/ground_truth/explorer/pose", "/ground_truth/follower/pose", "/tf"):
        assert topics[t].count >= 5
    assert topics["/fiducial_transforms"].count == 1
