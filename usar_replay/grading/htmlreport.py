"""``usar report``: one self-contained HTML page per run, and an index page.

Why a page: the rerun viewer is the place to dig into a run, but it takes a while to draw
without a GPU and needs an installed viewer; a TA marking forty runs, or a student reading
their grade, needs something a browser opens at once and that can be mailed. Each page holds a
map of the run (walls, obstacles, targets, true and stored markers, every robot's true path,
and the evidence point of every rubric line, numbered as in the table), the rubric table, and
the camera frame in which each marker was first detected. Everything is embedded (the picture
as PNG, the frames as the recorded image bytes), so a page is one file with no links out.

The robots, their camera topic and their colours come from the run's assignment
(:func:`usar_replay.world.assignment.of`): the US&R explorer and follower, or the ROS 2 final
project's ``robot1``. A robot's colour is the palette's entry at its index in the assignment, so
the first robot of every assignment looks the same.

matplotlib draws the map with its Agg backend (no display needed); this module is its only
importer.
"""

from __future__ import annotations

import base64
import html
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from usar_replay import __version__
from usar_replay.core import contract, msgs
from usar_replay.core.safe_text import html_text
from usar_replay.grading.labels import Label, diameter_pt, place
from usar_replay.grading.stored_markers import StoredMarkers, is_marker_topic
from usar_replay.grading.verdict import Check, GradeReport
from usar_replay.log.run import Run
from usar_replay.world.assignment import Assignment
from usar_replay.world.assignment import of as assignment_of
from usar_replay.world.scenario import Box, Cylinder, Scenario, Sphere

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "RunPicture",
    "collect",
    "detection_figure",
    "draw_map",
    "index_page",
    "map_png",
    "outline",
    "run_page",
]

FRAME_MEMORY = 64
"""Camera frames kept while waiting for their detections (a detection names its image's stamp
and arrives a few frames later at most)."""
ROBOT_PALETTE = ("#1f77b4", "#9467bd", "#8c564b", "#e377c2")
"""A robot's path colour, by its index in the assignment's robots (US&R: explorer blue, follower
purple; ROS 2: robot1 blue)."""
OTHER_ROBOT_COLOR = "#7f7f7f"


def robot_color(asg: Assignment, robot: str) -> str:
    """The robot's colour on the map (grey for a robot the assignment does not name)."""
    names = asg.robot_names
    if robot not in names:
        return OTHER_ROBOT_COLOR
    return ROBOT_PALETTE[names.index(robot) % len(ROBOT_PALETTE)]


@dataclass(slots=True)
class Detection:
    """The frame in which a marker was first detected."""

    marker_id: int
    t_ns: int
    image_format: str
    image: bytes
    corners: tuple[tuple[float, float], ...] = ()
    """The marker's outline in the image's pixels: its published pose (in the camera's optical
    frame) projected through the camera's ``K``; empty when that cannot be done."""
    size: tuple[int, int] = (0, 0)
    """The image's width and height (from its camera info)."""


@dataclass(slots=True)
class RunPicture:
    """What a page shows besides the grade: paths, stored markers, detection frames."""

    paths: dict[str, list[tuple[int, float, float]]] = field(default_factory=dict)
    """robot -> [(log time, x, y)] from ground truth."""
    stored: dict[int, tuple[float, float]] = field(default_factory=dict)
    """Marker ID -> stored (x, y) in ``map``, the mission's last stored markers
    (:mod:`usar_replay.grading.stored_markers`: its ``marker_poses``, or a pose topic)."""
    stored_on: str = ""
    """The topics they came from; where they were looked for, when none."""
    detections: list[Detection] = field(default_factory=list)

    def position(self, robot: str, t_ns: int) -> tuple[float, float] | None:
        """The robot's true position at (or just before) ``t_ns``."""
        path = self.paths.get(robot, [])
        best = None
        for t, x, y in path:
            if t > t_ns:
                break
            best = (x, y)
        return best if best is not None else (path[0][1:] if path else None)


_Pose = tuple[msgs.Vector3 | msgs.Point, msgs.Quaternion]


def _detected(topic: str, msg: msgs.Message | None) -> tuple[int, list[tuple[int, _Pose]]] | None:
    """The image stamp and (marker ID, pose in the camera's optical frame) of each detection
    in a detector's message: US&R's ``aruco_detect`` (``/fiducial_transforms``) or the ROS 2
    project's ``ros2_aruco`` (``/aruco_markers``); None for any other message."""
    if topic == contract.FIDUCIALS and isinstance(msg, msgs.FiducialTransformArray):
        return msg.header.stamp.ns, [
            (f.fiducial_id, (f.transform.translation, f.transform.rotation)) for f in msg.transforms
        ]
    if topic == contract.ARUCO_MARKERS and isinstance(msg, msgs.ArucoMarkers):
        return msg.header.stamp.ns, [
            (mid, (p.position, p.orientation))
            for mid, p in zip(msg.marker_ids, msg.poses, strict=False)
        ]
    return None


def collect(run: Run) -> RunPicture:
    """One pass over the log for the picture: true paths, stored markers, detection frames
    (the robots and the camera are the run's assignment's)."""
    asg = assignment_of(run.require_scenario())
    pic = RunPicture(paths={r: [] for r in asg.robot_names})
    truth = {contract.truth_pose(r): r for r in asg.robot_names}
    frames: dict[int, msgs.CompressedImage] = {}
    info: msgs.CameraInfo | None = None
    marker_size = run.settings.detector.marker_size
    detectors = [contract.FIDUCIALS, contract.ARUCO_MARKERS]
    scenario = run.require_scenario()
    stored = StoredMarkers((m.id, (m.x, m.y, m.z)) for m in scenario.markers)
    marker_topics = [t for t, info in run.topics.items() if is_marker_topic(t, info.msgtype)]
    topics = [*truth, *marker_topics, asg.image_topic, *detectors, asg.camera_info_topic]
    for m in run.messages(topics):
        msg = m.msg
        if isinstance(msg, msgs.CameraInfo):
            info = msg
        elif m.topic in truth and isinstance(msg, msgs.PoseStamped):
            p = msg.pose.position
            pic.paths[truth[m.topic]].append((m.log_time_ns, p.x, p.y))
        elif isinstance(msg, msgs.CompressedImage):
            frames[msg.header.stamp.ns] = msg
            if len(frames) > FRAME_MEMORY:
                del frames[next(iter(frames))]
        elif (found := _detected(m.topic, msg)) is not None:
            stamp_ns, ids = found
            seen = {d.marker_id for d in pic.detections}
            image = frames.get(stamp_ns)
            for mid, (position, rotation) in ids:
                if mid not in seen and image is not None:
                    seen.add(mid)
                    pic.detections.append(
                        Detection(
                            mid,
                            m.log_time_ns,
                            image.format,
                            image.data,
                            outline(position, rotation, info, marker_size),
                            (0, 0) if info is None else (info.width, info.height),
                        )
                    )
        elif msg is not None and m.publisher != "sim" and stored.note(m.topic, msg):
            pic.stored = {mid: (p[0], p[1]) for mid, p in stored.by_id.items()}
    pic.detections.sort(key=lambda d: d.marker_id)
    pic.stored_on = stored.where
    return pic


def outline(
    t: msgs.Vector3 | msgs.Point,
    q: msgs.Quaternion,
    info: msgs.CameraInfo | None,
    size: float,
) -> tuple[tuple[float, float], ...]:
    """A detected marker's corners in pixels: the square of side ``size`` (the detector's
    marker size) at the published pose, through ``K`` and plumb-bob distortion. Why not detect
    again: the page shows what the recorded detector published, with no image decode."""
    if info is None or len(info.k) < 9:
        return ()
    n = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if not n > 0.0 or not math.isfinite(n):
        return ()
    x, y, z, w = q.x / n, q.y / n, q.z / n, q.w / n
    rot = (
        (1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
        (2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
        (2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)),
    )
    k = info.k
    d = [*info.d, 0.0, 0.0, 0.0, 0.0, 0.0][:5]
    h = size / 2
    out = []
    for cx, cy in ((-h, h), (h, h), (h, -h), (-h, -h)):  # ArUco's corner order
        px, py, pz = (
            r[0] * cx + r[1] * cy + tv for r, tv in zip(rot, (t.x, t.y, t.z), strict=True)
        )
        if pz <= 1e-6:
            return ()
        a, b = px / pz, py / pz
        r2 = a * a + b * b
        radial = 1 + d[0] * r2 + d[1] * r2 * r2 + d[4] * r2 * r2 * r2
        a, b = (
            a * radial + 2 * d[2] * a * b + d[3] * (r2 + 2 * a * a),
            b * radial + d[2] * (r2 + 2 * b * b) + 2 * d[3] * a * b,
        )
        out.append((k[0] * a + k[1] * b + k[2], k[4] * b + k[5]))
    return tuple(out)


# --- the map --------------------------------------------------------------------------------------


def _robot_of(check: Check, asg: Assignment) -> str:
    """Whose position shows a line's evidence: the robot whose move the evidence cites
    (``follower moved``), else the robot the line is named after (``follower.home``), else for
    ``time_limit`` the last robot (US&R's mission ends when the follower is home), else the
    camera robot (it detects, broadcasts and stores the markers)."""
    robots = asg.robot_names
    for r in robots:
        if check.evidence == f"{r} moved":
            return r
    named = check.id.partition(".")[0]
    if named in robots:
        return named
    if check.id == "time_limit":
        return robots[-1]
    return asg.camera_robot


def _box_corners(b: Box) -> list[tuple[float, float]]:
    c, s = math.cos(b.yaw), math.sin(b.yaw)
    hx, hy = b.size_x / 2, b.size_y / 2
    return [
        (b.x + c * dx - s * dy, b.y + s * dx + c * dy)
        for dx, dy in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))
    ]


LABEL_FONT = 7
"""Points: the evidence circles' numbers."""


def evidence_labels(
    fig: Figure, ax: Axes, report: GradeReport, pic: RunPicture, asg: Assignment
) -> list[Label]:
    """The numbered circles of the map, placed (:func:`usar_replay.grading.labels.place`) in
    map metres on the finished layout, so that none covers another or crosses the frame. Lines
    evidenced at one spot share a circle ("7,8"); a text ends in ``+`` when all its lines
    passed, ``-`` otherwise (the colour)."""
    spots: dict[tuple[float, float], list[tuple[int, bool]]] = {}
    for n, c in enumerate(report.checks, start=1):
        at = None if c.evidence_ns is None else pic.position(_robot_of(c, asg), c.evidence_ns)
        if at is not None:
            spots.setdefault((round(at[0], 2), round(at[1], 2)), []).append((n, c.passed))
    ax.apply_aspect()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    (px0, _), (px1, _) = ax.transData.transform([(0.0, 0.0), (1.0, 0.0)])
    metres_per_pt = fig.dpi / 72.0 / abs(px1 - px0)
    wanted = []
    for at, lines in spots.items():
        text = ",".join(str(n) for n, _ in lines)
        r = diameter_pt(text, LABEL_FONT) / 2 * metres_per_pt
        wanted.append((text + ("+" if all(ok for _, ok in lines) else "-"), at, r))
    return place(wanted, (x0, x1, y0, y1), gap=1.5 * metres_per_pt)


def map_png(scenario: Scenario, report: GradeReport, pic: RunPicture) -> bytes:
    """The run seen from above, as PNG bytes."""
    fig, _ = draw_map(scenario, report, pic)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    return buf.getvalue()


def draw_map(
    scenario: Scenario, report: GradeReport, pic: RunPicture
) -> tuple[Figure, list[Label]]:
    """The map's figure and where its evidence circles went (the tests check those)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import patches
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 6.5), dpi=110)
    ax = fig.add_subplot()
    for b in scenario.walls:
        ax.add_patch(patches.Polygon(_box_corners(b), closed=True, color="#555555", lw=0))
    for b in scenario.boxes:
        ax.add_patch(patches.Polygon(_box_corners(b), closed=True, color="#b08d57", lw=0))
    round_things: list[Cylinder | Sphere] = [*scenario.cylinders, *scenario.spheres]
    for r in round_things:
        ax.add_patch(patches.Circle((r.x, r.y), r.radius, color="#b08d57", lw=0))
    asg = assignment_of(scenario)
    for robot, (sx, sy, _yaw) in zip(asg.robot_names, asg.starts(scenario), strict=True):
        color = robot_color(asg, robot)
        path = pic.paths.get(robot, [])
        if path:
            ax.plot([p[1] for p in path], [p[2] for p in path], color=color, lw=1.6,
                    label=f"{robot} (true path)")  # fmt: skip
        ax.plot(sx, sy, marker="s", ms=9, mfc="none", mec=color, mew=2)
    for k, (x, y) in enumerate(scenario.targets):
        ax.plot(x, y, marker="x", ms=9, mew=2, color="black")
        ax.annotate(f"target_{k + 1}", (x, y), xytext=(5, -12), textcoords="offset points",
                    fontsize=8)  # fmt: skip
    for i, m in enumerate(sorted(scenario.markers, key=lambda m: m.id)):
        ax.plot(m.x, m.y, marker="D", ms=8, color="#2ca02c", label="true marker" if not i else None)
        right = m.x > sum(t[0] for t in scenario.targets) / max(len(scenario.targets), 1)
        ax.annotate(f"marker {m.id}", (m.x, m.y), xytext=(-6 if right else 6, 6),
                    textcoords="offset points", ha="right" if right else "left", fontsize=8,
                    color="#2ca02c")  # fmt: skip
    for i, (_mid, (x, y)) in enumerate(sorted(pic.stored.items())):
        ax.plot(x, y, marker="o", ms=5, color="#ff7f0e", label="stored marker" if not i else None)
    ax.plot([], [], marker="o", ms=10, mfc="white", mec="#2ca02c", mew=2, ls="none",
            label="evidence (rubric line #)")  # fmt: skip
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m, map)")
    ax.set_ylabel("y (m, map)")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=5, fontsize=8, frameon=False)
    fig.tight_layout()
    labels = evidence_labels(fig, ax, report, pic, asg)
    for label in labels:
        color = "#2ca02c" if label.text.endswith("+") else "#d62728"
        if label.moved:
            ax.plot(*zip(label.anchor, label.center, strict=True), color=color, lw=0.8, zorder=5)
            ax.plot(*label.anchor, marker="o", ms=3, color=color, zorder=5)
        ax.add_patch(patches.Circle(label.center, label.radius, facecolor="white",
                                    edgecolor=color, lw=1.6, zorder=6))  # fmt: skip
        ax.annotate(label.text.rstrip("+-"), label.center, ha="center", va="center",
                    fontsize=LABEL_FONT, color=color, zorder=7)  # fmt: skip
    return fig, labels


# --- the pages ------------------------------------------------------------------------------------

_STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em auto;max-width:1100px;color:#222;padding:0 1em}
h1{font-size:1.4em;margin-bottom:.2em} .muted{color:#666}
.pass{color:#1a7f37;font-weight:600} .fail{color:#cf222e;font-weight:600}
table{border-collapse:collapse;width:100%;font-size:.9em;margin:1em 0}
th,td{border-bottom:1px solid #ddd;padding:.35em .5em;text-align:left;vertical-align:top}
th{background:#f6f8fa} td.num{text-align:right;white-space:nowrap}
img.map{width:100%;border:1px solid #ddd}
.frames{display:flex;flex-wrap:wrap;gap:1em} figure{margin:0}
figure img{max-width:320px;border:1px solid #ddd} figcaption{font-size:.85em;color:#555}
.det{display:flex;gap:.5em;align-items:flex-start} .det svg{border:1px solid #ddd}
svg.zoom image{image-rendering:pixelated}
""".strip()


def _data_uri(fmt: str, data: bytes) -> str:
    mime = "image/jpeg" if fmt.lower() in ("jpeg", "jpg") else "image/png"
    return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"


def _verdict(ok: bool) -> str:
    return f'<span class="{"pass" if ok else "fail"}">{"PASS" if ok else "FAIL"}</span>'


def _page(title: str, body: str) -> str:
    return (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        f"<title>{html_text(title)}</title><style>{_STYLE}</style></head>"
        f"<body>{body}<p class='muted'>usar-replay {html.escape(__version__)}</p></body></html>\n"
    )


def run_page(run: Run, report: GradeReport, pic: RunPicture) -> str:
    """One run's page."""
    e = html_text  # every string: controls escaped, then HTML's escapes
    scenario = run.require_scenario()
    verdict = _verdict(report.passed and report.log_complete)
    parts = [
        f"<h1>{e(str(run.path))}</h1>",
        f"<p>{verdict} &nbsp; <b>{report.points:.4g} / {report.max_points:.4g}</b> points"
        f" &middot; world <b>{e(scenario.name)}</b> &middot; {run.duration_s:.1f} s of sim time"
        f" &middot; file {e(run.file_state)}"
        + ("" if run.outcome == "unknown" else f" &middot; mission {e(run.outcome)}")
        + "</p>",
    ]
    if report.started_with:
        parts.append(f"<p>Started with: <code>{e(report.started_with)}</code></p>")
    if not report.log_complete:
        parts.append(
            f"<p class='fail'>The log is incomplete ({e(report.log_problem)}); "
            "graded as far as it goes.</p>"
        )
    png = map_png(scenario, report, pic)
    parts.append("<h2>The run</h2>")
    parts.append(
        f"<img class='map' alt='map of the run' src='{_data_uri('png', png)}'>"
        "<p class='muted'>Walls grey, obstacles brown, true markers green, stored markers "
        "orange; squares are the robots' starts. Numbered circles: where the robot was at each "
        "rubric line's evidence time (green passed, red failed).</p>"
        + (
            f"<p class='muted'>Stored markers from {e(pic.stored_on)}.</p>"
            if pic.stored
            else f"<p class='muted'>No stored markers; looked on {e(pic.stored_on)}.</p>"
        )
    )
    rows = [
        "<tr><th>#</th><th></th><th>rubric line</th><th>measured</th><th>needed</th>"
        "<th>points</th><th>at (sim time)</th></tr>"
    ]
    for n, c in enumerate(report.checks, start=1):
        at = "" if c.evidence_ns is None else f"{c.evidence_ns / 1e9:.1f} s ({e(c.evidence)})"
        rows.append(
            f"<tr><td class='num'>{n}</td><td>{_verdict(c.passed)}</td>"
            f"<td><code>{e(c.id)}</code><br>{e(c.description)}</td><td>{e(c.measured)}</td>"
            f"<td>{e(c.threshold)}</td><td class='num'>{c.points:.3g}/{c.max_points:.3g}</td>"
            f"<td>{at}</td></tr>"
        )
    parts.append("<h2>Rubric</h2><table>" + "".join(rows) + "</table>")
    parts.append("<h2>Detections</h2>")
    if pic.detections:
        figs = [detection_figure(d) for d in pic.detections]
        parts.append("<div class='frames'>" + "".join(figs) + "</div>")
    else:
        parts.append("<p>No marker was detected.</p>")
    return _page(f"usar report: {run.path.name}", "\n".join(parts))


ZOOM_BELOW = 0.15
"""A marker narrower than this share of the frame's width gets a zoomed inset beside it."""
FRAME_PX = 320
"""Width of a frame on the page."""


def detection_figure(d: Detection) -> str:
    """A detection frame with the detected marker's outline drawn over it (SVG over the
    recorded bytes: nothing is decoded or re-encoded) and, for a marker seen from far away, a
    zoomed inset of it, so a person can see what was detected."""
    uri = _data_uri(d.image_format, d.image)
    caption = f"marker {d.marker_id}: first detected at {d.t_ns / 1e9:.1f} s"
    w, h = d.size
    if not d.corners or not w or not h:
        return (
            f"<figure><img alt='marker {d.marker_id}' src='{uri}'>"
            f"<figcaption>{caption}</figcaption></figure>"
        )
    pts = " ".join(f"{u:.1f},{v:.1f}" for u, v in d.corners)
    us, vs = [u for u, _ in d.corners], [v for _, v in d.corners]
    side = max(max(us) - min(us), max(vs) - min(vs), 1.0)
    body = [_svg_frame(d, uri, (0.0, 0.0, float(w), float(h)), pts, FRAME_PX, "frame")]
    if side < ZOOM_BELOW * w:
        half = side / 2 + max(side * 0.6, 6.0)
        cu, cv = (max(us) + min(us)) / 2, (max(vs) + min(vs)) / 2
        # the inset stays inside the frame where it can (a marker at the edge is not centred)
        bx = min(max(cu - half, 0.0), max(w - 2 * half, 0.0))
        by = min(max(cv - half, 0.0), max(h - 2 * half, 0.0))
        box = (bx, by, 2 * half, 2 * half)
        zoom = FRAME_PX / 2 / (2 * half)
        body.append(_svg_frame(d, uri, box, pts, FRAME_PX // 2, "zoom"))
        caption += f" ({side:.0f} px wide; zoomed {zoom:.0f}x on the right)"
    return (
        "<figure><div class='det'>" + "".join(body) + "</div>"
        f"<figcaption>{caption}; outline: the published pose</figcaption></figure>"
    )


def _svg_frame(
    d: Detection, uri: str, view: tuple[float, float, float, float], pts: str, width: int, kind: str
) -> str:
    x, y, w, h = view
    mid, (iw, ih) = d.marker_id, d.size
    height = round(width * h / w)
    return (
        f"<svg class='{kind}' role='img' aria-label='marker {mid} ({kind})' width='{width}' "
        f"height='{height}' viewBox='{x:.1f} {y:.1f} {w:.1f} {h:.1f}'>"
        f"<image href='{uri}' x='0' y='0' width='{iw}' height='{ih}'/>"
        f"<polygon points='{pts}' fill='none' stroke='#ff1493' stroke-width='2' "
        "vector-effect='non-scaling-stroke'/></svg>"
    )


def index_page(
    entries: Sequence[tuple[str, str, GradeReport | None, str]],
) -> str:
    """The index: (recording, page file name, report or None, error) per run."""
    e = html_text  # every string: controls escaped, then HTML's escapes
    rows = ["<tr><th>recording</th><th></th><th>points</th><th>failed lines</th></tr>"]
    for source, page, report, error in entries:
        if report is None:
            rows.append(
                f"<tr><td>{e(source)}</td><td class='fail'>ERROR</td><td></td>"
                f"<td>{e(error)}</td></tr>"
            )
            continue
        ok = report.passed and report.log_complete
        failed = ", ".join(report.failed_ids()) + ("" if report.log_complete else " (incomplete)")
        rows.append(
            f"<tr><td><a href='{e(page)}'>{e(source)}</a></td><td>{_verdict(ok)}</td>"
            f"<td class='num'>{report.points:.4g}/{report.max_points:.4g}</td>"
            f"<td>{e(failed)}</td></tr>"
        )
    passed = sum(1 for _, _, r, _ in entries if r is not None and r.passed and r.log_complete)
    body = (
        f"<h1>usar report</h1><p>{passed}/{len(entries)} recordings pass</p>"
        f"<table>{''.join(rows)}</table>"
    )
    return _page("usar report", body)


def page_names(sources: Sequence[str]) -> list[str]:
    """A distinct ``NAME.html`` per recording (``run.html``, ``run-2.html`` for two ``run.mcap``
    in different folders)."""
    names: list[str] = []
    used: set[str] = set()
    for src in sources:
        stem = Path(src).name.removesuffix(".mcap") or "run"
        name, k = f"{stem}.html", 2
        while name in used or name == "index.html":
            name, k = f"{stem}-{k}.html", k + 1
        used.add(name)
        names.append(name)
    return names


def output_paths(out_dir: str | os.PathLike[str], sources: Sequence[str]) -> list[Path]:
    """Every file ``usar report`` will write: the pages, then ``index.html``."""
    d = Path(out_dir)
    return [*(d / n for n in page_names(sources)), d / "index.html"]
