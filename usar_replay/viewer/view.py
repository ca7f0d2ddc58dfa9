"""`usar view`: a recording in the rerun viewer. The only module that imports ``rerun``.

What is shown is decided by :mod:`usar_replay.viewer.scene` (pure: messages -> columns per entity);
this module hands those columns to rerun and lays the views out:

* **sending**: each entity goes out with ONE ``send_columns`` call on one timeline,
  :data:`TIMELINE` (a *duration* column: sim time is time since the simulator started, not a
  wall-clock date, so a timestamp column would print 1970 dates). Only the camera images go out
  while the log streams, in chunks of :data:`IMAGE_BATCH_BYTES`, so memory stays bounded. Row by
  row, ``rr.log`` measured 80-110 us per row (archetype construction plus ``set_time``): 5-6 s for
  the ~60k rows of an 8-minute course log on top of reading it;
* **the layout**: :func:`build_blueprint`;
* **where the view goes**: :mod:`usar_replay.viewer.viewer_process` (an ``.rrd`` written to a
  temporary name and renamed when complete, the native viewer, or the web viewer).

The log is read through an opened :class:`usar_replay.log.run.Run` (the caller opens it once); the
bag decoder and the grader are imported inside :func:`view_run`, the workflow entry point.
"""

from __future__ import annotations

import contextlib
import errno
import os
import time
import uuid
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from usar_replay.core import contract, msgs, rotations
from usar_replay.core.errors import UsageError, UsarError
from usar_replay.viewer import scene as sc
from usar_replay.viewer.scene import ImageBatch, Scene, Strips
from usar_replay.viewer.viewer_process import (
    DEFAULT_BIND,
    Output,
    ViewerProcess,
    check_rrd,
    default_rrd_path,
)
from usar_replay.world.assignment import Assignment
from usar_replay.world.assignment import of as assignment_of
from usar_replay.world.scenario import Box, Scenario, building_extent

if TYPE_CHECKING:
    from usar_replay.grading.grade import GradeReport
    from usar_replay.log.run import Run

__all__ = [
    "APPLICATION_ID",
    "TIMELINE",
    "ViewResult",
    "build_blueprint",
    "send_scene",
    "view_run",
    "wait_until_interrupted",
]

APPLICATION_ID = "usar-replay"
TIMELINE = "sim_time"
"""The one timeline: sim time in nanoseconds, as a duration (the log's time axis)."""
IMAGE_BATCH_BYTES = 8 << 20
"""Camera images go out in chunks of about this many bytes while the log streams: memory stays
bounded, and rerun writes many small chunks much faster than one big one (measured on a course
log: 4776 frames, 164 MB of PNG, one chunk 4.0 s, 8 MB chunks 0.3 s); the viewer also pages
small chunks in and out better."""


def _duration(times: Sequence[int]) -> rr.TimeColumn:
    return rr.TimeColumn(TIMELINE, duration=np.asarray(times, dtype=np.int64).view("m8[ns]"))


# --- sending a scene -----------------------------------------------------------------------------


def send_images(rec: rr.RecordingStream, scene: Scene, batch: ImageBatch) -> None:
    """One batch of camera images as ``EncodedImage`` rows (the recorded bytes, not decoded)."""
    if batch.times:
        rec.send_columns(
            scene.image_entity,
            indexes=[_duration(batch.times)],
            columns=rr.EncodedImage.columns(blob=batch.blobs, media_type=batch.media_types),
        )


def send_scene(rec: rr.RecordingStream, scene: Scene) -> None:
    """Send every collected column (each entity once), the static world and the blueprint.

    ``scene`` must be closed (:meth:`Scene.close`); images still pending are sent first.
    """
    send_images(rec, scene, scene.take_images())
    rec.log(sc.MAP_ENTITY, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    if scene.scenario is not None:
        _send_world(rec, scene.scenario)
    _send_tf(rec, scene)
    _send_camera(rec, scene)
    _send_robots(rec, scene)
    _send_markers(rec, scene)
    for entity, (times, values) in sorted(scene.scalars.items()):
        linear = entity.endswith("linear_x")
        robot = entity.split("/")[2]
        name = "linear.x (m/s)" if linear else "angular.z (rad/s)"
        color = scene.robot_color(robot) if linear else sc.ANGULAR_COLOR
        rec.log(entity, rr.SeriesLines(names=name, colors=color, widths=1.5), static=True)
        rec.send_columns(
            entity,
            indexes=[_duration(times)],
            columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)),
        )
    for entity, col in sorted(scene.texts.items()):
        rec.send_columns(
            entity,
            indexes=[_duration(col.times)],
            columns=rr.TextLog.columns(text=col.texts, level=col.levels),
        )
    scn = scene.scenario
    extent = building_extent(scn) if scn is not None and scn.walls else None
    camera = f"{scene.assignment.camera_robot} camera + detections"
    blueprint = build_blueprint(scene.pinhole_entity, scene.plotted_robots(), extent, camera)
    rec.send_blueprint(blueprint)


def _solid_boxes(items: Sequence[Box], color: tuple[int, int, int]) -> rr.Boxes3D:
    return rr.Boxes3D(
        centers=[(b.x, b.y, b.z) for b in items],
        sizes=[(b.size_x, b.size_y, b.size_z) for b in items],
        quaternions=[rotations.xyzw_from_yaw(b.yaw) for b in items],
        colors=color,
        fill_mode=rr.components.FillMode.Solid,
    )


def _send_world(rec: rr.RecordingStream, scn: Scenario) -> None:
    """The building, obstacles, markers, targets and homes, all static."""
    world = sc.WORLD_ENTITY
    solid = rr.components.FillMode.Solid
    if scn.walls:
        rec.log(f"{world}/walls", _solid_boxes(scn.walls, sc.WALL_COLOR), static=True)
        xmin, ymin, xmax, ymax = building_extent(scn)
        floor = rr.Boxes3D(
            mins=[(xmin, ymin, -0.02)],
            sizes=[(xmax - xmin, ymax - ymin, 0.02)],
            colors=sc.FLOOR_COLOR,
            fill_mode=solid,
        )
        rec.log(f"{world}/floor", floor, static=True)
    if scn.boxes:
        rec.log(f"{world}/boxes", _solid_boxes(scn.boxes, sc.OBSTACLE_COLOR), static=True)
    if scn.cylinders:
        cylinders = rr.Cylinders3D(
            lengths=[c.height for c in scn.cylinders],
            radii=[c.radius for c in scn.cylinders],
            centers=[(c.x, c.y, c.height / 2) for c in scn.cylinders],
            colors=sc.OBSTACLE_COLOR,
            fill_mode=solid,
        )
        rec.log(f"{world}/cylinders", cylinders, static=True)
    if scn.spheres:
        spheres = rr.Ellipsoids3D(
            half_sizes=[(s.radius,) * 3 for s in scn.spheres],
            centers=[(s.x, s.y, s.radius) for s in scn.spheres],
            colors=sc.OBSTACLE_COLOR,
            fill_mode=solid,
        )
        rec.log(f"{world}/spheres", spheres, static=True)
    if scn.markers:
        markers = rr.Boxes3D(
            centers=[(m.x, m.y, m.z) for m in scn.markers],
            sizes=[(0.008, m.size, m.size) for m in scn.markers],
            quaternions=[rotations.xyzw_from_yaw(m.yaw) for m in scn.markers],
            colors=(250, 250, 250),
            fill_mode=solid,
            labels=[f"marker {m.id}" for m in scn.markers],
        )
        rec.log(f"{world}/markers", markers, static=True)
    if scn.targets:
        targets = rr.Points3D(
            [(x, y, 0.01) for x, y in scn.targets],
            radii=0.06,
            colors=sc.TARGET_COLOR,
            labels=[f"target_{i + 1}" for i in range(len(scn.targets))],
        )
        rec.log(sc.TARGETS_ENTITY, targets, static=True)
    asg = assignment_of(scn)
    homes = list(zip(asg.robot_names, asg.starts(scn), strict=True))
    points = rr.Points3D(
        [(x, y, 0.01) for _, (x, y, _) in homes],
        radii=0.04,
        colors=[sc.robot_color(name, asg.robot_names) for name, _ in homes],
        labels=[f"{name} home" for name, _ in homes],
    )
    rec.log(sc.HOMES_ENTITY, points, static=True)


def _body(robot: str, color: tuple[int, int, int], *, solid: bool) -> rr.Boxes3D:
    centre, half = sc.robot_body()
    mode = rr.components.FillMode.Solid if solid else rr.components.FillMode.MajorWireframe
    return rr.Boxes3D(
        centers=[centre],
        half_sizes=[half],
        colors=color,
        fill_mode=mode,
        labels=[robot] if solid else None,
    )


def _send_tf(rec: rr.RecordingStream, scene: Scene) -> None:
    paths = scene.frame_paths
    for frame, path in sorted(paths.items()):
        length = 0.15 if frame == contract.MARKER_FRAME else 0.1
        rec.log(path, rr.TransformAxes3D(axis_length=length), static=True)
    for child, (xyz, quat) in sorted(scene.tf_static.items()):
        tf = rr.Transform3D(translation=xyz, quaternion=rr.Quaternion(xyzw=quat))
        rec.log(paths[child], tf, static=True)
    for child, col in sorted(scene.tf_dynamic.items()):
        rec.send_columns(
            paths[child],
            indexes=[_duration(col.times)],
            columns=rr.Transform3D.columns(
                translation=np.asarray(col.translations, dtype=np.float64),
                quaternion=np.asarray(col.quaternions, dtype=np.float64),
            ),
        )
    for robot, entity in scene.body_entities().items():
        rec.log(entity, _body(robot, scene.robot_color(robot), solid=True), static=True)


def _send_camera(rec: rr.RecordingStream, scene: Scene) -> None:
    info = scene.camera_info
    if info is not None and info.width and info.height:
        pinhole = rr.Pinhole(
            image_from_camera=np.asarray(info.k, dtype=np.float64).reshape(3, 3),
            resolution=[info.width, info.height],
            camera_xyz=rr.ViewCoordinates.RDF,
            image_plane_distance=0.4,
        )
        rec.log(scene.pinhole_entity, pinhole, static=True)
    rows = scene.detections
    if rows.times:
        n = len(rows.items)
        rec.send_columns(
            scene.detections_entity,
            indexes=[_duration(rows.times)],
            columns=rr.LineStrips2D.columns(
                strips=rows.items,
                labels=rows.labels,
                colors=[sc.DETECTION_COLOR] * n,
                radii=[1.5] * n,
            ).partition(rows.lengths),
        )


def _send_strips3d(
    rec: rr.RecordingStream,
    entity: str,
    rows: Strips,
    color: tuple[int, int, int],
    radius: float,
) -> None:
    n = len(rows.items)
    rec.send_columns(
        entity,
        indexes=[_duration(rows.times)],
        columns=rr.LineStrips3D.columns(strips=rows.items, colors=[color] * n, radii=[radius] * n),
    )


def _send_robots(rec: rr.RecordingStream, scene: Scene) -> None:
    for robot, poses in sorted(scene.truth.items()):
        entity = f"{sc.TRUTH_ENTITY}/{robot}"
        rec.log(entity + "/body", _body(robot, scene.robot_color(robot), solid=False), static=True)
        rec.send_columns(
            entity,
            indexes=[_duration(poses.times)],
            columns=rr.Transform3D.columns(
                translation=np.asarray(poses.translations, dtype=np.float64),
                quaternion=np.asarray(poses.quaternions, dtype=np.float64),
            ),
        )
    for robot, path in sorted(scene.paths.items()):
        entity = f"{sc.TRUTH_ENTITY}/{robot}_path"
        _send_strips3d(rec, entity, path.rows, scene.robot_color(robot), 0.01)
    for robot, rows in sorted(scene.goals.items()):
        n = len(rows.items)
        rec.send_columns(
            f"{sc.MAP_ENTITY}/{robot}/goal",
            indexes=[_duration(rows.times)],
            columns=rr.Arrows3D.columns(
                origins=[o for o, _ in rows.items],
                vectors=[v for _, v in rows.items],
                labels=rows.labels,
                colors=[scene.robot_color(robot)] * n,
                radii=[0.02] * n,
            ),
        )
    for robot, rows in sorted(scene.plans.items()):
        entity = f"{sc.MAP_ENTITY}/{robot}/plan"
        _send_strips3d(rec, entity, rows, scene.robot_color(robot), 0.005)


def _send_markers(rec: rr.RecordingStream, scene: Scene) -> None:
    # Labels of the true and stored markers show on hover only: drawn, they would sit on top
    # of the marker's own label; the red marker_frame labels (with the error) stay drawn.
    layers = (
        (sc.TRUE_MARKERS_ENTITY, scene.true_markers, sc.TRUE_MARKER_COLOR, 0.03, False),
        (sc.STORED_MARKERS_ENTITY, scene.stored_markers, sc.STORED_MARKER_COLOR, 0.025, False),
        (sc.MARKER_FRAME_ENTITY, scene.marker_frame_rows, sc.MARKER_FRAME_COLOR, 0.02, True),
    )
    for entity, rows, color, radius, shown in layers:
        if not rows.times:
            continue
        n = len(rows.items)
        rec.log(entity, rr.Points3D.from_fields(show_labels=shown), static=True)
        rec.send_columns(
            entity,
            indexes=[_duration(rows.times)],
            columns=rr.Points3D.columns(
                positions=np.asarray(rows.items, dtype=np.float64).reshape(-1, 3),
                labels=rows.labels,
                colors=[color] * n,
                radii=[radius] * n,
            ).partition(rows.lengths),
        )


# --- layout --------------------------------------------------------------------------------------


def build_blueprint(
    pinhole_entity: str,
    robots: Sequence[str],
    extent: tuple[float, float, float, float] | None = None,
    camera_name: str = "camera + detections",
) -> rrb.Blueprint:
    """The ready layout: the building in 3D and the log on the left; camera and plots right.

    ``extent`` (xmin, ymin, xmax, ymax of the walls) places the 3D eye south of the building,
    looking down at about 55 degrees, so the rooms are seen over the walls rather than through
    them (rerun's automatic eye looks from near the floor).
    """
    eye = None
    if extent is not None:
        xmin, ymin, xmax, ymax = extent
        cx, cy = (xmin + xmax) / 2, (ymin + ymax) / 2
        span = max(xmax - xmin, ymax - ymin, 1.0)
        eye = rrb.EyeControls3D(
            position=(cx, cy - 0.55 * span, 0.8 * span),
            look_target=(cx, cy, 0.0),
            eye_up=(0.0, 0.0, 1.0),
        )
    plots: list[rrb.View] = [
        rrb.TimeSeriesView(origin=f"{sc.PLOTS_ENTITY}/{r}", name=f"{r} cmd_vel") for r in robots
    ] or [rrb.TimeSeriesView(origin=sc.PLOTS_ENTITY, name="cmd_vel")]
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial3DView(origin=sc.MAP_ENTITY, name="building (map)", eye_controls=eye),
                rrb.TextLogView(origin=sc.LOGS_ENTITY, name="log (rosout, goals, grade)"),
                row_shares=[3, 1],
            ),
            rrb.Vertical(
                rrb.Spatial2DView(origin=pinhole_entity, name=camera_name),
                *plots,
                row_shares=[2] + [1] * len(plots),
            ),
            column_shares=[3, 2],
        ),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline=TIMELINE),
        auto_views=False,
    )


# --- where the view goes -------------------------------------------------------------------------


# --- the viewer process --------------------------------------------------------------------------


# --- the workflow --------------------------------------------------------------------------------


@dataclass(slots=True)
class ViewResult:
    """What :func:`view_run` did; ``problem`` is one line when the log was not whole."""

    rrd: Path | None
    url: str | None
    spawned: bool
    frames: int
    messages: int
    seconds: float
    problem: str = ""
    grade_problem: str = ""
    viewer_problem: str = ""
    """Set when the native viewer could not be used and the view went to a file instead."""
    viewer: ViewerProcess | None = field(default=None, repr=False)
    """The web viewer's server, kept while it serves (stopped by :func:`wait_until_interrupted`)."""


class _Decoder:
    """Decodes only what the viewer draws; CameraInfo only when it changes (not its stamp).

    Odometry is skipped: ``odom -> base_footprint`` on ``/tf`` carries the same pose, and the two
    odometry topics are a quarter of a course log's messages. A payload that does not decode is
    counted and skipped (the rest of the log is still shown). The odometry and camera-info topics
    are the run's assignment's.
    """

    def __init__(self, asg: Assignment) -> None:
        from usar_replay.log import bag

        self._decode = bag.decode
        self._skip = frozenset(contract.odom(r) for r in asg.robot_names)
        self._camera_info_topic = asg.camera_info_topic
        self._info_tail: bytes | None = None
        self.failures = 0
        self.first_failure = ""

    def __call__(self, topic: str, msgtype: str, data: bytes, t_ns: int) -> msgs.Message | None:
        if topic in self._skip:
            return None
        if topic == self._camera_info_topic:
            tail = data[12:]  # CDR: 4 bytes encapsulation, then the 8-byte stamp
            if tail == self._info_tail:
                return None
            self._info_tail = tail
        try:
            return self._decode(data, msgtype)
        except KeyError:
            return None  # a type usar-replay does not know: nothing to draw
        except Exception as err:  # noqa: BLE001 - a corrupt payload: skip it, say so once
            self.failures += 1
            if not self.first_failure:
                self.first_failure = f"{topic} at {t_ns / 1e9:.3f} s: {type(err).__name__}"
            return None


def _log_problem(run: Run, decode: _Decoder) -> str:
    """One line on what is damaged: the file, its attachments, undecodable messages."""
    parts = [run.problem(), *run.problems]
    if decode.failures:
        parts.append(
            f"{decode.failures} messages could not be decoded (first: {decode.first_failure})"
        )
    return "; ".join(p for p in parts if p)


def _stream(
    rec: rr.RecordingStream, run: Run, report: GradeReport | None, grade_problem: str
) -> tuple[Scene, str]:
    """Read the run once into a scene (images sent as they come), then send the scene.

    The stream is flushed with a deadline before rerun's own (unbounded) flush on leaving
    it: when a write failed (a full disk, a file size limit), rerun's file sink has stopped,
    and a flush without a deadline waited for it forever (seen once in 15 runs). Then no
    flush without a deadline runs, at exit either (:func:`rerun.unregister_shutdown`)."""
    rec.__enter__()
    flushed = False
    try:
        sent = _send_run(rec, run, report, grade_problem)
        try:
            rec.flush(timeout_sec=FLUSH_TIMEOUT_S)
        except Exception as err:  # rerun's error for a flush past its deadline
            raise RuntimeError(f"rerun's writer did not finish: {_first_line(err)}") from err
        flushed = True
    finally:
        if flushed:
            rec.__exit__(None, None, None)  # finalises file sinks; nothing left to wait for
        else:
            rr.unregister_shutdown()
    return sent


def _send_run(
    rec: rr.RecordingStream, run: Run, report: GradeReport | None, grade_problem: str
) -> tuple[Scene, str]:
    """:func:`_stream`'s sending: the run's messages, then the scene; (scene, log problem)."""
    rec.send_recording_name(run.path.stem)
    scene = Scene(run.scenario, marker_size=run.settings.detector.marker_size)
    decode = _Decoder(scene.assignment)
    for m in run.messages(decode=False):
        scene.feed(m.topic, decode(m.topic, m.msgtype, m.data, m.log_time_ns), m.log_time_ns)
        if scene.pending_image_bytes >= IMAGE_BATCH_BYTES:
            send_images(rec, scene, scene.take_images())
    scene.close()
    problem = _log_problem(run, decode)
    if problem:
        scene.add_note(f"incomplete log: {problem}")
    if report is not None:
        scene.add_grade(report)
    if grade_problem:
        scene.add_note(grade_problem, "ERROR")
    send_scene(rec, scene)
    return scene, problem


FLUSH_TIMEOUT_S = 120.0
"""Wall seconds the view's last flush may take (a safety net: it takes well under a second)."""


def _write_failed(rrd: Path, part: Path, err: BaseException) -> UsageError:
    """rerun's file writer says only that it stopped; a probe write beside the file finds the
    reason (a full disk, a file size limit) while the partial file still holds its space."""
    probe = part.with_name(part.name + ".probe")
    reason = ""
    try:
        with open(probe, "wb") as f:
            f.write(bytes(1 << 20))
            f.flush()
            os.fsync(f.fileno())
    except OSError as probe_err:
        if probe_err.errno == errno.ENOSPC:
            return UsageError(f"{rrd}: the disk is full; free some space and run again")
        reason = probe_err.strerror or str(probe_err)
    finally:
        with contextlib.suppress(OSError):
            probe.unlink()
    return UsageError(
        f"{rrd}: cannot write the view ({reason or _first_line(err)}); choose another path"
    )


def _start_viewer(
    log: Path, output: Output, *, overwrite: bool, grpc_port: int, web_port: int, bind: str
) -> tuple[ViewerProcess | None, Output, str]:
    """Start the viewer ``output`` asks for. A native viewer that cannot start is replaced by
    the file next to the log (returned, with why); a web viewer that cannot start is an error."""
    if not (output.spawn or output.web):
        return None, output, ""
    try:
        viewer = ViewerProcess.start(
            web=output.web, bind=bind, grpc_port=grpc_port, web_port=web_port
        )
    except UsageError as err:
        if output.web:
            raise
        fallback = default_rrd_path(log)
        try:
            check_rrd(fallback, log, overwrite=overwrite, option="")
        except UsageError as no_file:
            raise UsageError(f"{err}; and {no_file}") from no_file
        return None, Output(rrd=fallback), str(err)
    return viewer, output, ""


def _temporary(rrd: Path) -> Path:
    """The temporary file beside ``rrd`` that rerun writes (renamed to ``rrd`` when done)."""
    part = rrd.with_name(f".{rrd.name}.{os.getpid()}.part")
    try:
        rrd.parent.mkdir(parents=True, exist_ok=True)
        part.touch()
    except OSError as err:
        raise UsageError(f"{rrd}: cannot write here ({err.strerror}); choose another path") from err
    return part


def view_run(
    run: Run,
    output: Output,
    *,
    grade: bool = False,
    overwrite: bool = False,
    grpc_port: int = 9876,
    web_port: int = 9090,
    bind: str = DEFAULT_BIND,
) -> ViewResult:
    """Send the opened ``run`` to ``output``, reading its messages once; see the module docs.

    An ``.rrd`` is written to a temporary name beside it and renamed when complete (nothing is
    left behind on failure; an existing file is replaced only with ``overwrite``). A damaged log
    is shown as far as it goes, and :attr:`ViewResult.problem` says what is damaged. When the
    native viewer cannot start, the view goes to the file next to the log instead and
    :attr:`ViewResult.viewer_problem` says why.
    """
    started = time.perf_counter()
    report: GradeReport | None = None
    grade_problem = ""
    if grade:
        # the grader's own pass, not one riding along on this one: the rubric lines must be
        # exactly what `usar grade` reports (it decodes only the few topics it needs)
        from usar_replay.grading.grade import grade_run

        try:
            report = grade_run(run)
        except UsarError as err:
            grade_problem = f"cannot grade: {err}"
    viewer, output, viewer_problem = _start_viewer(
        run.path, output, overwrite=overwrite, grpc_port=grpc_port, web_port=web_port, bind=bind
    )
    part: Path | None = None
    try:
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=uuid.uuid4())
        sinks: list[Any] = []
        if output.rrd is not None:
            part = _temporary(output.rrd)
            sinks.append(rr.FileSink(part))
        if viewer is not None:
            sinks.append(rr.GrpcSink(viewer.grpc_url))
        rec.set_sinks(*sinks)
        try:
            scene, problem = _stream(rec, run, report, grade_problem)
        except RuntimeError as err:  # rerun's sinks: the file writer or the viewer failed
            if output.rrd is not None and part is not None:
                raise _write_failed(output.rrd, part, err) from err
            raise UsageError(
                f"the rerun viewer went away while the view was sent ({_first_line(err)}); "
                "open it again, or write a file with --save OUT.rrd"
            ) from err
        if part is not None and output.rrd is not None:
            if output.rrd.exists() and not overwrite:
                raise UsageError(f"{output.rrd}: appeared while this command ran; left as it is")
            os.replace(part, output.rrd)
    except BaseException:
        if viewer is not None:
            viewer.stop()
        raise
    finally:
        if part is not None:
            with contextlib.suppress(FileNotFoundError):
                part.unlink()
    return ViewResult(
        rrd=output.rrd,
        url=viewer.web_url if viewer is not None else None,
        spawned=output.spawn,
        frames=scene.images_taken,
        messages=scene.messages,
        seconds=time.perf_counter() - started,
        problem=problem,
        grade_problem=grade_problem,
        viewer_problem=viewer_problem,
        viewer=viewer if output.web else None,
    )


def _first_line(err: BaseException) -> str:
    return (str(err).strip().splitlines() or [type(err).__name__])[0][:160]


def wait_until_interrupted(result: ViewResult, poll_s: float = 1.0) -> None:
    """Keep the web viewer serving until Ctrl-C (the KeyboardInterrupt goes on to the caller);
    its server process is stopped either way."""
    try:
        proc = result.viewer.proc if result.viewer is not None else None
        while proc is None or proc.poll() is None:
            time.sleep(poll_s)
    finally:
        if result.viewer is not None:
            result.viewer.stop()
