"""A tf2-exact transform buffer, broadcaster and listener over :mod:`usar_replay.core.msgs`.

Students of this course learn tf2 with ROS; this buffer answers every lookup as tf2's
``BufferCore`` does (same tree walk, same latest-common-time rule, same interpolation, same
exceptions and message texts), so what they learn here holds on a real robot.

``lookup_transform(target, source, time)`` returns the pose of ``source`` in ``target``: the
transform that maps points expressed in ``source`` into ``target``. ``time`` is integer
nanoseconds or a :class:`msgs.Time`; ``0`` means "the latest time at which the whole chain is
known" (tf2's ``getLatestCommonTime``: the minimum over the dynamic links on the path of each
link's newest stamp; static links are ignored).

The course's pitfalls, explained
--------------------------------
* **Why ``marker_frame`` can be looked up at the image's stamp.** The broadcaster stamps
  ``marker_frame`` with the camera image's stamp. Its parent chain
  (``camera_rgb_optical_frame -> camera_rgb_frame -> base_footprint``) is static, and
  ``base_footprint -> odom`` is published by the simulator at every control tick, including the
  tick at which the frame was rendered; ``odom -> map`` is static. So every link on the path has a
  sample at (or on both sides of) that stamp, and ``marker_frame`` itself has exactly one sample
  at exactly that stamp. Looking it up *at that stamp* needs no extrapolation.
* **"Lookup would require extrapolation ..."** appears when a link has no data around the
  requested time: asking for ``marker_frame`` at "now" (later than its only sample: *into the
  future* for that link), or at time 0 after a newer ``marker_frame`` made the chain's latest
  common time move, or before the robot's odometry started (*into the past*). A link with a
  single sample answers only its own stamp ("at time X, but only time Y is in the buffer"). tf2
  never extrapolates; neither does this buffer.
* **"\"marker_frame\" passed to lookupTransform argument source_frame does not exist"** appears
  when the frame was never broadcast: no marker was detected yet (``marker_frame`` is broadcast
  only on frames with a detection), or the name is misspelt (tf2 frame ids have no leading
  '/'; a leading '/' is an InvalidArgument).
* **A frame looked up in itself** is the identity, before any check of the frame: tf2 answers
  it even for a frame that was never broadcast (stamped with the requested time, or for time 0
  with the frame's newest stamp, 0 when it has none), and ``can_transform`` says True.
  ``lookup_transform_full`` is stricter: its three frames must exist.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from math import isnan
from typing import Any, Literal, overload

from usar_replay.core import contract, msgs

__all__ = [
    "MAX_FRAMES",
    "BufferCore",
    "ConnectivityException",
    "ExtrapolationException",
    "InvalidArgumentException",
    "LookupException",
    "StaticTfMessageBuilder",
    "TimeoutException",
    "TfMessageBuilder",
    "TransformException",
    "BufferFeeder",
]


class _Log:
    """The module's logger, made on first use: :mod:`logging` costs ``usar grade`` a few ms
    to import, and a log whose transforms are all accepted never logs."""

    def __getattr__(self, name: str) -> Any:
        import logging

        return getattr(logging.getLogger("usar_replay.core.tf_tree"), name)


log = _Log()

MAX_GRAPH_DEPTH = 1000
NS = 1_000_000_000
QUATERNION_NORMALIZATION_TOLERANCE = 10e-3  # on |q|^2 - 1, as tf2's buffer_core.cpp

Vec = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # x, y, z, w

_ZERO: Vec = (0.0, 0.0, 0.0)
_UNIT: Quat = (0.0, 0.0, 0.0, 1.0)


class TransformException(Exception):
    """Base of tf2's lookup errors."""


class LookupException(TransformException):
    """A frame that the buffer has never seen."""


class ConnectivityException(TransformException):
    """Two frames that are not in the same tree."""


class ExtrapolationException(TransformException):
    """A time outside the data a link holds (tf2 never extrapolates)."""


class InvalidArgumentException(TransformException):
    """An empty frame id, or one with a leading '/'."""


class TimeoutException(TransformException):
    """Kept for API parity with tf2_ros; this buffer never waits."""


# --- quaternion math in plain floats: the hot path of every lookup ------------------------------


def _qmul(a: Quat, b: Quat) -> Quat:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def _qrot(q: Quat, v: Vec) -> Vec:
    x, y, z, w = q
    vx, vy, vz = v
    # t = 2 q_vec x v ; v' = v + w t + q_vec x t
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (
        vx + w * tx + (y * tz - z * ty),
        vy + w * ty + (z * tx - x * tz),
        vz + w * tz + (x * ty - y * tx),
    )


def _chain(t: Vec, q: Quat, acc_t: Vec, acc_q: Quat) -> tuple[Vec, Quat]:
    """``(t, q) * (acc_t, acc_q)``: one more link toward the root, in one call (hot path).

    The same arithmetic as ``_qrot(q, acc_t) + t`` and ``_qmul(q, acc_q)``, inlined.
    """
    x, y, z, w = q
    vx, vy, vz = acc_t
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    bx, by, bz, bw = acc_q
    return (
        vx + w * tx + (y * tz - z * ty) + t[0],
        vy + w * ty + (z * tx - x * tz) + t[1],
        vz + w * tz + (x * ty - y * tx) + t[2],
    ), (
        w * bx + x * bw + y * bz - z * by,
        w * by - x * bz + y * bw + z * bx,
        w * bz + x * by - y * bx + z * bw,
        w * bw - x * bx - y * by - z * bz,
    )


def _qinv(q: Quat) -> Quat:
    x, y, z, w = q
    n = x * x + y * y + z * z + w * w
    return (-x / n, -y / n, -z / n, w / n)


def _slerp(a: Quat, b: Quat, t: float) -> Quat:
    """Shortest-path spherical interpolation, as tf2's ``slerp`` of ``tf2::Quaternion``.

    Unrolled by hand: it runs once per dynamic link of every interpolated lookup.
    """
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    dot = ax * bx + ay * by + az * bz + aw * bw
    if dot < 0.0:
        bx, by, bz, bw, dot = -bx, -by, -bz, -bw, -dot
    if dot > 0.9999999:
        x, y, z, w = ax + (bx - ax) * t, ay + (by - ay) * t, az + (bz - az) * t, aw + (bw - aw) * t
    else:
        theta = math.acos(min(dot, 1.0))
        s = math.sin(theta)
        wa, wb = math.sin((1.0 - t) * theta) / s, math.sin(t * theta) / s
        x, y, z, w = ax * wa + bx * wb, ay * wa + by * wb, az * wa + bz * wb, aw * wa + bw * wb
    n = math.sqrt(x * x + y * y + z * z + w * w)
    return (x / n, y / n, z / n, w / n)


def _strip_slash(frame: str) -> str:
    """tf2's ``stripSlash``: one leading '/' goes (a second one stays)."""
    return frame[1:] if frame[:1] == "/" else frame


def _seconds(ns: int) -> str:
    """Times in tf2's error texts: seconds with six decimals."""
    return f"{ns / NS:.6f}"


# --- caches --------------------------------------------------------------------------------------


@dataclass(slots=True)
class _Sample:
    stamp: int
    parent: str
    t: Vec
    q: Quat


@dataclass(slots=True)
class _TimeCache:
    """One child frame's history, sorted by stamp (tf2's ``TimeCache`` / ``StaticCache``).

    tf2 keeps its list newest first; here it is oldest first, so tf2's "front" is ``[-1]``.
    Samples that share a stamp are all kept, in insertion order (tf2 (ROS 2) drops only an
    exact duplicate); a lookup at the newest stamp or in the middle gets the last inserted of
    that stamp, at the oldest stamp the first inserted, as tf2's ``findClosest`` does.

    The exact-duplicate check at a shared stamp looks in a set of that stamp's samples (made
    the first time a stamp is shared), not along them: a message with thousands of distinct
    transforms of one child at one stamp (a grade bomb) costs linear time, not quadratic.
    """

    max_storage_ns: int
    stamps: list[int] = field(default_factory=list)
    samples: list[_Sample] = field(default_factory=list)
    static: bool = False
    _shared: dict[int, set[tuple[str, Vec, Quat]]] = field(default_factory=dict)
    """(parent, t, q) of the samples at each stamp that more than one sample has had."""

    def insert(self, s: _Sample) -> bool:
        """tf2's ``insertData``: prune by the newest stamp *before* the insert, refuse data
        older than that newest minus the storage time, drop an exact duplicate (still True)."""
        if self.static:
            self.stamps, self.samples = [s.stamp], [s]
            return True
        stamps = self.stamps
        if stamps:
            oldest_kept = stamps[-1] - self.max_storage_ns
            if stamps[0] < oldest_kept:
                cut = bisect.bisect_left(stamps, oldest_kept)
                del stamps[:cut]
                del self.samples[:cut]
                for old in [t for t in self._shared if t < oldest_kept]:
                    del self._shared[old]
            if s.stamp < oldest_kept:
                return False
        if not stamps or s.stamp > stamps[-1]:  # the usual case, newer than all: no search
            stamps.append(s.stamp)
            self.samples.append(s)
            return True
        i = bisect.bisect_right(stamps, s.stamp)
        seen = self._shared.get(s.stamp)
        if seen is None:
            lo = bisect.bisect_left(stamps, s.stamp)
            seen = {(d.parent, d.t, d.q) for d in self.samples[lo:i]}
            self._shared[s.stamp] = seen
        key = (s.parent, s.t, s.q)
        if key in seen:
            return True  # an exact repeat: tf2 keeps one copy and reports success
        seen.add(key)
        stamps.insert(i, s.stamp)
        self.samples.insert(i, s)
        return True

    def clear(self) -> None:
        """tf2's ``clearList``: a dynamic history empties, a static transform stays."""
        if not self.static:
            self.stamps.clear()
            self.samples.clear()
            self._shared.clear()

    def latest(self) -> tuple[int, str]:
        """(newest stamp, its parent); static caches report stamp 0, as tf2's StaticCache."""
        if not self.samples:
            return 0, ""
        return (0 if self.static else self.stamps[-1]), self.samples[-1].parent

    def get(self, time: int) -> tuple[_Sample | None, str]:
        """The sample at ``time`` (interpolated), or None and tf2's error text."""
        samples = self.samples
        if self.static and samples:
            return samples[0], ""
        stamps = self.stamps
        if not stamps:
            return None, (
                f"Lookup would require extrapolation at time {_seconds(time)}, but only time "
                f"{_seconds(0)} is in the buffer"
            )
        if time == 0:
            return samples[-1], ""
        if len(stamps) == 1:
            if stamps[0] == time:
                return samples[0], ""
            return None, (
                f"Lookup would require extrapolation at time {_seconds(time)}, but only time "
                f"{_seconds(stamps[0])} is in the buffer"
            )
        if time == stamps[-1]:
            return samples[-1], ""
        if time == stamps[0]:
            return samples[0], ""
        if time > stamps[-1]:
            return None, (
                "Lookup would require extrapolation into the future.  Requested time "
                f"{_seconds(time)} but the latest data is at time {_seconds(stamps[-1])}"
            )
        if time < stamps[0]:
            return None, (
                "Lookup would require extrapolation into the past.  Requested time "
                f"{_seconds(time)} but the earliest data is at time {_seconds(stamps[0])}"
            )
        i = bisect.bisect_right(stamps, time) - 1
        one = samples[i]
        if one.stamp == time:
            return one, ""
        two = samples[i + 1]
        if one.parent != two.parent:
            return one, ""  # tf2 does not interpolate across a change of parent
        r = (time - one.stamp) / (two.stamp - one.stamp)
        t = (
            one.t[0] + (two.t[0] - one.t[0]) * r,
            one.t[1] + (two.t[1] - one.t[1]) * r,
            one.t[2] + (two.t[2] - one.t[2]) * r,
        )
        return _Sample(time, one.parent, t, _slerp(one.q, two.q, r)), ""


# --- the buffer ----------------------------------------------------------------------------------


MAX_FRAMES = 4096
"""Frame names one buffer holds (the course's tree has about a dozen; a package's own tree a
few dozen more). Past it a transform naming a new frame is dropped and counted
(:attr:`BufferCore.dropped`): each name costs a cache of its own, so without a cap a ``/tf``
flood of new names (a red team's 477,000 in 2.5 sim-s, issue 44) grew the recorder and the
grader by about 1.1 KB a name, for good."""


class BufferCore:
    """tf2's ``BufferCore`` with tf2_ros' Python ``Buffer`` API (no waiting: data is the log).

    At most ``max_frames`` frame names (:data:`MAX_FRAMES`): a transform naming one more is
    dropped (False, tf2's log says so once), counted in :attr:`dropped`."""

    def __init__(self, cache_time: float = 10.0, max_frames: int = MAX_FRAMES) -> None:
        self.cache_time_ns = round(cache_time * NS)
        self.max_frames = max_frames
        self.dropped = 0
        """Transforms dropped because they named a frame past :attr:`max_frames`."""
        self._frames: dict[str, _TimeCache] = {}
        # every frame id ever named by an accepted-looking insert, in first-seen order (tf2's
        # frame numbers: the child is numbered before its parent); clear() keeps them, as tf2
        self._ids: dict[str, None] = {}
        self._authority: dict[str, str] = {}

    # -- inserting -----------------------------------------------------------------------------

    def set_transform(
        self, msg: msgs.TransformStamped, authority: str = "default_authority"
    ) -> bool:
        """Insert a dynamic transform; False (with tf2's warning) when it is refused."""
        return self._set(msg, authority, static=False)

    def set_transform_static(
        self, msg: msgs.TransformStamped, authority: str = "default_authority"
    ) -> bool:
        """Insert a static transform: it holds at every time."""
        return self._set(msg, authority, static=True)

    def _set(self, msg: msgs.TransformStamped, authority: str, *, static: bool) -> bool:
        """tf2's ``setTransformImpl``: every check logs its error, then any error refuses.

        Written for speed (``usar grade`` inserts every ``/tf`` transform of a log): the checks
        are one condition here, and only a refused transform goes through :meth:`_refuse`,
        which logs each failing check as tf2 does."""
        child = msg.child_frame_id
        if child[:1] == "/":  # tf2's stripSlash, as _strip_slash
            child = child[1:]
        header = msg.header
        parent = header.frame_id
        if parent[:1] == "/":
            parent = parent[1:]
        transform = msg.transform
        tr, rot = transform.translation, transform.rotation
        x, y, z = tr.x, tr.y, tr.z
        qx, qy, qz, qw = rot.x, rot.y, rot.z, rot.w
        norm2 = qx * qx + qy * qy + qz * qz + qw * qw
        if (
            child == parent
            or not child
            or not parent
            or isnan(x)
            or isnan(y)
            or isnan(z)
            or isnan(qx)
            or isnan(qy)
            or isnan(qz)
            or isnan(qw)
            or not abs(norm2 - 1.0) < QUATERNION_NORMALIZATION_TOLERANCE
        ):
            self._refuse(child, parent, tr, rot, authority)
            return False
        norm = math.sqrt(norm2)
        q = (qx / norm, qy / norm, qz / norm, qw / norm)
        # tf2 numbers the child, then the parent, before it tries the insert
        ids = self._ids
        if len(ids) >= self.max_frames - 1 and (child not in ids or parent not in ids):
            new = (child not in ids) + (parent not in ids)
            if len(ids) + new > self.max_frames:
                if not self.dropped:
                    log.warning(
                        "usar: more than %d frame names: transforms naming another frame are "
                        "dropped (the first: %s -> %s)",
                        self.max_frames,
                        parent,
                        child,
                    )
                self.dropped += 1
                return False
        if child not in ids:
            ids[child] = None
        if parent not in ids:
            ids[parent] = None
        cache = self._frames.get(child)
        if cache is None or cache.static != static:
            # a new frame, or a dynamic frame turned static (or back): tf2 allocates a new cache
            cache = _TimeCache(self.cache_time_ns, static=static)
            self._frames[child] = cache
        st = header.stamp
        stamp = st.sec * NS + st.nanosec  # Time.ns
        if not cache.insert(_Sample(stamp, parent, (x, y, z), q)):
            log.warning(
                "TF_OLD_DATA ignoring data from the past for frame %s at time %s according to "
                "authority %s\nPossible reasons are listed at "
                "http://wiki.ros.org/tf/Errors%%20explained",
                child,
                _seconds(stamp),
                authority,
            )
            return False
        self._authority[child] = authority
        return True

    def _refuse(
        self, child: str, parent: str, tr: msgs.Vector3, rot: msgs.Quaternion, authority: str
    ) -> None:
        """tf2's errors for a refused transform: every failing check, in tf2's order."""
        if child == parent:
            log.error(
                'TF_SELF_TRANSFORM: Ignoring transform from authority "%s" with frame_id and  '
                'child_frame_id "%s" because they are the same',
                authority,
                child,
            )
        if not child:
            log.error(
                'TF_NO_CHILD_FRAME_ID: Ignoring transform from authority "%s" because '
                "child_frame_id not set ",
                authority,
            )
        if not parent:
            log.error(
                'TF_NO_FRAME_ID: Ignoring transform with child_frame_id "%s"  from '
                'authority "%s" because frame_id not set',
                child,
                authority,
            )
        if any(math.isnan(v) for v in (tr.x, tr.y, tr.z, rot.x, rot.y, rot.z, rot.w)):
            log.error(
                'TF_NAN_INPUT: Ignoring transform for child_frame_id "%s" from authority "%s" '
                "because of a nan value in the transform (%f %f %f) (%f %f %f %f)",
                child,
                authority,
                tr.x,
                tr.y,
                tr.z,
                rot.x,
                rot.y,
                rot.z,
                rot.w,
            )
        norm2 = rot.x * rot.x + rot.y * rot.y + rot.z * rot.z + rot.w * rot.w
        if not abs(norm2 - 1.0) < QUATERNION_NORMALIZATION_TOLERANCE:  # NaN fails too, as tf2
            log.error(
                'TF_DENORMALIZED_QUATERNION: Ignoring transform for child_frame_id "%s" '
                'from authority "%s" because of an invalid quaternion in the transform '
                "(%f %f %f %f)",
                child,
                authority,
                rot.x,
                rot.y,
                rot.z,
                rot.w,
            )

    def clear(self) -> None:
        """tf2's ``clear``: dynamic histories empty; frame ids and static transforms stay."""
        for cache in self._frames.values():
            cache.clear()

    # -- looking up ----------------------------------------------------------------------------

    @staticmethod
    def _ns(time: int | msgs.Time) -> int:
        return time.ns if isinstance(time, msgs.Time) else int(time)

    def _check(self, where: str, frame: str) -> str:
        """tf2's ``validateFrameId`` in its no-throw form: "" when valid, else the reason."""
        if not frame:
            return (
                f'Invalid frame ID "{frame}" passed to {where} - in tf2 frame_ids cannot be empty'
            )
        if frame[0] == "/":
            return (
                f'Invalid frame ID "{frame}" passed to {where} - in tf2 frame_ids cannot start '
                "with a '/'"
            )
        if frame not in self._ids:
            return f'Invalid frame ID "{frame}" passed to {where} - frame does not exist'
        return ""

    def _validate(self, where: str, frame: str) -> None:
        """tf2's throwing ``validateFrameId``."""
        if not frame:
            raise InvalidArgumentException(
                f'Invalid argument "{frame}" passed to {where} - in tf2 frame_ids cannot be empty'
            )
        if frame[0] == "/":
            raise InvalidArgumentException(
                f'Invalid argument "{frame}" passed to {where} - in tf2 frame_ids cannot start '
                "with a '/'"
            )
        if frame not in self._ids:
            raise LookupException(f'"{frame}" passed to {where} does not exist. ')

    def _identity_time(self, frame: str, time: int) -> int:
        """The stamp of a lookup of a frame in itself: ``time``, or for time 0 the frame's
        newest stamp (0 when it is static, has no history, or is unknown), as tf2."""
        if time == 0:
            cache = self._frames.get(frame)
            if cache is not None:
                return cache.latest()[0]
        return time

    def lookup_transform(
        self, target_frame: str, source_frame: str, time: int | msgs.Time
    ) -> msgs.TransformStamped:
        """The pose of ``source_frame`` in ``target_frame`` at ``time`` (0: latest common).

        A frame looked up in itself is the identity, before any check of the frame (tf2's
        short cut: even an unknown or empty frame id answers).
        """
        ns = time.ns if isinstance(time, msgs.Time) else int(time)
        if target_frame == source_frame:
            return _stamped(
                target_frame, source_frame, self._identity_time(target_frame, ns), _ZERO, _UNIT
            )
        self._validate("lookupTransform argument target_frame", target_frame)
        self._validate("lookupTransform argument source_frame", source_frame)
        t, q, stamp = self._walk(target_frame, source_frame, ns)
        return _stamped(target_frame, source_frame, stamp, t, q)

    def _lookup_impl(self, target: str, source: str, time: int) -> tuple[Vec, Quat, int]:
        """tf2's ``lookupTransformImpl`` after validation (the full lookup's two halves)."""
        if target == source:
            return _ZERO, _UNIT, self._identity_time(target, time)
        return self._walk(target, source, time)

    def lookup_transform_full(
        self,
        target_frame: str,
        target_time: int | msgs.Time,
        source_frame: str,
        source_time: int | msgs.Time,
        fixed_frame: str,
    ) -> msgs.TransformStamped:
        """tf2's time travel: ``source`` at ``source_time`` into ``target`` at ``target_time``,
        through ``fixed_frame`` (a frame assumed not to move between the two times).

        As tf2: all three frames must exist (no identity short cut here), and the stamp is the
        target half's (``fixed -> target`` at ``target_time``).
        """
        self._validate("lookupTransform argument target_frame", target_frame)
        self._validate("lookupTransform argument source_frame", source_frame)
        self._validate("lookupTransform argument fixed_frame", fixed_frame)
        t1, q1, _ = self._lookup_impl(fixed_frame, source_frame, self._ns(source_time))
        t2, q2, s2 = self._lookup_impl(target_frame, fixed_frame, self._ns(target_time))
        t = _qrot(q2, t1)
        return _stamped(
            target_frame,
            source_frame,
            s2,
            (t[0] + t2[0], t[1] + t2[1], t[2] + t2[2]),
            _qmul(q2, q1),
        )

    @overload
    def can_transform(
        self,
        target_frame: str,
        source_frame: str,
        time: int | msgs.Time,
        return_debug_tuple: Literal[False] = False,
    ) -> bool: ...

    @overload
    def can_transform(
        self,
        target_frame: str,
        source_frame: str,
        time: int | msgs.Time,
        return_debug_tuple: Literal[True],
    ) -> tuple[bool, str]: ...

    def can_transform(
        self,
        target_frame: str,
        source_frame: str,
        time: int | msgs.Time,
        return_debug_tuple: bool = False,
    ) -> bool | tuple[bool, str]:
        """Whether :meth:`lookup_transform` would succeed; never raises. With
        ``return_debug_tuple`` it answers ``(ok, tf2's error text)``, as tf2_ros."""
        result = self._can(target_frame, source_frame, self._ns(time))
        return result if return_debug_tuple else result[0]

    def _can(self, target: str, source: str, time: int) -> tuple[bool, str]:
        if target == source:
            return True, ""  # tf2's short cut, before the frames are checked
        err = self._check("canTransform argument target_frame", target) or self._check(
            "canTransform argument source_frame", source
        )
        if err:
            return False, err
        return self._can_internal(target, source, time)

    def _can_internal(self, target: str, source: str, time: int) -> tuple[bool, str]:
        """tf2's ``canTransformInternal`` on validated frames."""
        if target == source:
            return True, ""
        try:
            self._walk(target, source, time)
        except TransformException as e:
            return False, str(e)
        return True, ""

    @overload
    def can_transform_full(
        self,
        target_frame: str,
        target_time: int | msgs.Time,
        source_frame: str,
        source_time: int | msgs.Time,
        fixed_frame: str,
        return_debug_tuple: Literal[False] = False,
    ) -> bool: ...

    @overload
    def can_transform_full(
        self,
        target_frame: str,
        target_time: int | msgs.Time,
        source_frame: str,
        source_time: int | msgs.Time,
        fixed_frame: str,
        return_debug_tuple: Literal[True],
    ) -> tuple[bool, str]: ...

    def can_transform_full(
        self,
        target_frame: str,
        target_time: int | msgs.Time,
        source_frame: str,
        source_time: int | msgs.Time,
        fixed_frame: str,
        return_debug_tuple: bool = False,
    ) -> bool | tuple[bool, str]:
        """Whether :meth:`lookup_transform_full` would succeed (all three frames must exist)."""
        err = (
            self._check("canTransform argument target_frame", target_frame)
            or self._check("canTransform argument source_frame", source_frame)
            or self._check("canTransform argument fixed_frame", fixed_frame)
        )
        result = (False, err)
        if not err:
            result = self._can_internal(target_frame, fixed_frame, self._ns(target_time))
            if result[0]:
                result = self._can_internal(fixed_frame, source_frame, self._ns(source_time))
        return result if return_debug_tuple else result[0]

    def get_latest_common_time(self, target_frame: str, source_frame: str) -> int:
        """tf2_py's ``get_latest_common_time`` in nanoseconds (0 when the path is all static).

        As tf2_py: both frames are validated (also when they are the same frame), and a
        failure of the walk is a plain :class:`TransformException` (not its subclasses).
        """
        self._validate("get_latest_common_time", target_frame)
        self._validate("get_latest_common_time", source_frame)
        try:
            return self._latest_common_time(target_frame, source_frame)
        except TransformException as e:
            raise TransformException(str(e)) from None

    def _latest_common_time(self, target: str, source: str) -> int:
        inf = math.inf
        if source == target:
            cache = self._frames.get(source)
            return cache.latest()[0] if cache else 0
        # tf2's order: the source's chain first, then the target's up to a common parent
        lct: list[tuple[int, str]] = []
        common: float = inf
        frame = source
        depth = 0
        while frame:
            cache = self._frames.get(frame)
            if cache is None:
                break
            latest, parent = cache.latest()
            if not parent:
                break
            if latest != 0:
                common = min(common, latest)
            lct.append((latest, parent))
            frame = parent
            if frame == target:
                return 0 if common == inf else int(common)
            depth += 1
            if depth > MAX_GRAPH_DEPTH:
                raise self._loop_error()
        frame = target
        common_parent = ""
        common = inf
        depth = 0
        while True:
            cache = self._frames.get(frame)
            if cache is None:
                break
            latest, parent = cache.latest()
            if not parent:
                break
            if latest != 0:
                common = min(common, latest)
            if any(p == parent for _, p in lct):
                common_parent = parent
                break
            frame = parent
            if frame == source:
                return 0 if common == inf else int(common)
            depth += 1
            if depth > MAX_GRAPH_DEPTH:
                raise self._loop_error()
        if not common_parent:
            raise ConnectivityException(_connectivity_text(target, source))
        for latest, parent in lct:
            if latest != 0:
                common = min(common, latest)
            if parent == common_parent:
                break
        return 0 if common == inf else int(common)

    def _walk(self, target: str, source: str, time: int) -> tuple[Vec, Quat, int]:
        """tf2's ``walkToTopParent`` + ``TransformAccum``: (translation, rotation, time used)."""
        if source == target:
            return _ZERO, _UNIT, time  # tf2's ``Identity`` ending (callers short-cut before)
        if time == 0:
            time = self._latest_common_time(target, source)
        # walk from the source toward the root
        s_t: Vec = (0.0, 0.0, 0.0)
        s_q: Quat = (0.0, 0.0, 0.0, 1.0)
        frame = source
        top_parent = frame
        extrapolation_error = ""
        extrapolation_might_have_occurred = False
        depth = 0
        while frame:
            cache = self._frames.get(frame)
            if cache is None:
                top_parent = frame
                break
            sample, err = cache.get(time)
            if sample is None:
                if not extrapolation_might_have_occurred:
                    extrapolation_error = err
                top_parent = frame
                extrapolation_might_have_occurred = True
                break
            if frame == target:
                return s_t, s_q, time  # the target is a parent of the source
            s_t, s_q = _chain(sample.t, sample.q, s_t, s_q)
            top_parent = frame
            frame = sample.parent
            depth += 1
            if depth > MAX_GRAPH_DEPTH:
                raise self._loop_error()
        # walk from the target toward the same top
        t_t: Vec = (0.0, 0.0, 0.0)
        t_q: Quat = (0.0, 0.0, 0.0, 1.0)
        frame = target
        depth = 0
        while frame != top_parent:
            cache = self._frames.get(frame)
            if cache is None:
                break
            sample, err = cache.get(time)
            if sample is None:
                raise ExtrapolationException(
                    f"{err}, when looking up transform from frame [{source}] to frame [{target}]"
                )
            if frame == source:
                inv = _qinv(t_q)
                v = _qrot(inv, (-t_t[0], -t_t[1], -t_t[2]))
                return v, inv, time  # the source is a parent of the target
            t_t, t_q = _chain(sample.t, sample.q, t_t, t_q)
            frame = sample.parent
            depth += 1
            if depth > MAX_GRAPH_DEPTH:
                raise self._loop_error()
        if frame != top_parent:
            if extrapolation_might_have_occurred:
                raise ExtrapolationException(
                    f"{extrapolation_error}, when looking up transform from frame [{source}] "
                    f"to frame [{target}]"
                )
            raise ConnectivityException(_connectivity_text(target, source))
        inv = _qinv(t_q)
        inv_t = _qrot(inv, (-t_t[0], -t_t[1], -t_t[2]))
        r = _qrot(inv, s_t)
        return (r[0] + inv_t[0], r[1] + inv_t[1], r[2] + inv_t[2]), _qmul(inv, s_q), time

    # -- introspection -------------------------------------------------------------------------

    def frames(self) -> dict[str, str]:
        """child -> parent (its newest sample's parent), sorted by child: the tree to draw."""
        return {
            c: self._frames[c].samples[-1].parent
            for c in sorted(self._frames)
            if self._frames[c].samples
        }

    def all_frames_as_yaml(self) -> str:
        """tf2's ``allFramesAsYAML``-like listing: parent, authority, newest/oldest stamps."""
        lines = []
        for child, parent in self.frames().items():
            cache = self._frames[child]
            lines += [
                f"{child}:",
                f"  parent: '{parent}'",
                f"  broadcaster: '{self._authority.get(child, '')}'",
                f"  most_recent_transform: {_seconds(cache.latest()[0])}",
                f"  oldest_transform: {_seconds(0 if cache.static else cache.stamps[0])}",
                f"  static: {str(cache.static).lower()}",
            ]
        return "\n".join(lines) + ("\n" if lines else "")

    def all_frames_as_string(self) -> str:
        """tf2's ``allFramesAsString``: every frame with a cache, in tf2's frame-number order
        (first seen), its parent at time 0 or ``NO_PARENT`` when its history is empty."""
        lines = []
        for frame in self._ids:
            cache = self._frames.get(frame)
            if cache is not None:
                sample, _ = cache.get(0)
                parent = sample.parent if sample is not None else "NO_PARENT"
                lines.append(f"Frame {frame} exists with parent {parent}.\n")
        return "".join(lines)

    def _loop_error(self) -> LookupException:
        """tf2 reports a loop in the tree as a LookupException listing every frame."""
        return LookupException(
            "The tf tree is invalid because it contains a loop.\n"
            + self.all_frames_as_string()
            + "\n"
        )


def _stamped(target: str, source: str, stamp: int, t: Vec, q: Quat) -> msgs.TransformStamped:
    n = math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    return msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(stamp), frame_id=target),
        child_frame_id=source,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=t[0], y=t[1], z=t[2]),
            rotation=msgs.Quaternion(x=q[0] / n, y=q[1] / n, z=q[2] / n, w=q[3] / n),
        ),
    )


def _connectivity_text(target: str, source: str) -> str:
    return (
        f"Could not find a connection between '{target}' and '{source}' because they are not "
        "part of the same tree.Tf has two or more unconnected trees."
    )


# --- broadcaster and listener -------------------------------------------------------------------


class TfMessageBuilder:
    """Turns transforms into the ``TFMessage`` to publish on ``/tf`` (the caller publishes)."""

    topic = contract.TF

    def send_transform(
        self, transform: msgs.TransformStamped | Sequence[msgs.TransformStamped]
    ) -> msgs.TFMessage:
        items = (transform,) if isinstance(transform, msgs.TransformStamped) else tuple(transform)
        return msgs.TFMessage(transforms=items)


class StaticTfMessageBuilder(TfMessageBuilder):
    """The same for ``/tf_static`` (latched: transient-local QoS in the log)."""

    topic = contract.TF_STATIC


class BufferFeeder:
    """Feeds a :class:`BufferCore` from ``/tf`` and ``/tf_static`` messages (tf2_ros' listener
    without a node)."""

    def __init__(self, buffer: BufferCore, authority: str = "listener") -> None:
        self.buffer = buffer
        self.authority = authority

    def on_tf(self, msg: msgs.TFMessage) -> None:
        for t in msg.transforms:
            self.buffer.set_transform(t, self.authority)

    def on_tf_static(self, msg: msgs.TFMessage) -> None:
        for t in msg.transforms:
            self.buffer.set_transform_static(t, self.authority)

    def feed(self, topic: str, msg: msgs.TFMessage) -> None:
        (self.on_tf_static if topic == contract.TF_STATIC else self.on_tf)(msg)


def frames_of(messages: Iterable[msgs.TFMessage]) -> set[str]:
    """Every frame id named in some TF messages (used by the viewer to build the tree)."""
    out: set[str] = set()
    for m in messages:
        for t in m.transforms:
            out.add(t.header.frame_id)
            out.add(t.child_frame_id)
    return out
