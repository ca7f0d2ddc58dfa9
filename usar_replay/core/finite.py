"""Finite numbers only: where a message holds NaN or infinity, by field name.

Why it matters for a grade: a comparison with NaN is always false, so "error > threshold"
never fails on a NaN error and a rubric line that asks "is the worst error over the limit?"
passes a marker at NaN metres (the issue's "worst error -100.0 cm"). A NaN ``cmd_vel`` turns the
simulator's physics to NaN. So every float a mission publishes is checked twice: at the call
(:meth:`usar_replay.node.executor.Executor.publish` raises :class:`NonFiniteValue` naming the
field) and again by the recorder on what crosses the process boundary
(:mod:`usar_replay.node.boundary_check`), since the mission process can be modified.

Pure and cheap: the walk follows :func:`usar_replay.core.msgs.field_kinds` (resolved once per
class) and skips bytes, strings and integers; a tuple of floats is checked in one pass.
"""

from __future__ import annotations

import math
from typing import Any

from usar_replay.core import msgs

__all__ = ["NonFiniteValue", "check_finite", "nonfinite_field"]


class NonFiniteValue(ValueError):
    """A message holds NaN or infinity; the message names the field (``linear.x = nan``)."""


def nonfinite_field(msg: msgs.Message) -> str:
    """The dotted path and value of the first non-finite float in ``msg``
    (``transforms[0].transform.translation.x = inf``); empty when every float is finite."""
    return _walk(msg, "")


def check_finite(topic: str, msg: msgs.Message) -> None:
    """Raise :class:`NonFiniteValue` when ``msg`` (to be published on ``topic``) holds NaN/inf."""
    where = _walk(msg, "")
    if where:
        raise NonFiniteValue(
            f"{topic}: {type(msg).__name__}.{where}: NaN and infinity are refused (a "
            "non-finite pose, velocity or detection cannot be simulated or graded)"
        )


def _walk(msg: Any, path: str) -> str:
    for name, kind, _elem in msgs.field_kinds(type(msg)):
        value = getattr(msg, name)
        if kind == "float":
            if not math.isfinite(value):
                return f"{path}{name} = {value!r}"
        elif kind == "msg":
            found = _walk(value, f"{path}{name}.")
            if found:
                return found
        elif kind == "msgs":
            for i, item in enumerate(value):
                found = _walk(item, f"{path}{name}[{i}].")
                if found:
                    return found
        elif kind == "floats" and not all(map(math.isfinite, value)):
            i = next(i for i, v in enumerate(value) if not math.isfinite(v))
            return f"{path}{name}[{i}] = {value[i]!r}"
    return ""
