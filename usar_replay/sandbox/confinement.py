"""One answer to "is untrusted code confined here?", for every caller that runs it.

Why one: a mission (:mod:`usar_replay.process.mission_process`), a ROS 1 build
(:mod:`usar_replay.ros1.building.workspace`) and a code tool (:mod:`usar_replay.code.tools`) each
asked it in their own words, and they must agree: a workspace built for the sandbox's fixed
paths runs only in the sandbox, and a batch must never grade with confinement on for one part
and off for another. The policy: ``off`` (``--no-sandbox``, or ``USAR_SANDBOX=off`` where the
caller says ``auto``) never confines; otherwise bubblewrap confines where it can make its
namespaces here; ``required`` refuses to go on without it (a batch), ``auto`` goes on
unconfined, warning once where asked to.

Whatever usar says about going without the sandbox says, in the same line, what that costs: a
mission run unconfined can read every file usar can, the hidden worlds' key included.
"""

from __future__ import annotations

import os
import sys
from typing import Literal

from usar_replay.core.errors import UsageError
from usar_replay.sandbox import kernel_sandbox

__all__ = ["UNCONFINED_COST", "Mode", "confined", "refusal"]

Mode = Literal["auto", "required", "off"]

UNCONFINED_COST = "unconfined, a mission can read every file usar can, the world key included"
"""What running without the sandbox costs, said wherever usar names a way to do it."""

_warned = False


def _mode(mode: str) -> str:
    if mode not in ("auto", "required", "off"):
        raise ValueError(f"sandbox mode {mode!r}: expected auto, required or off")
    if mode == "auto" and os.environ.get("USAR_SANDBOX", "").strip().lower() == "off":
        return "off"
    return mode


def _remedy() -> str:
    """How to get the sandbox: installing bubblewrap only where it is not installed (in a
    container with bwrap, installing it again changes nothing; the run's flags do)."""
    doctor = "give it what `usar doctor` names (in a container: the flags it lists)"
    if kernel_sandbox.installed():
        return doctor
    return f"install it ({kernel_sandbox.INSTALL_HINT}) or {doctor}"


def refusal(why: str, what: str = "usar") -> str:
    """The one line usar stops with where the sandbox cannot start (``why``: bubblewrap's own
    words): how to get it, where to look, and what going without it costs."""
    return (
        f"{why}: {what} will not run untrusted code without a kernel sandbox; {_remedy()}; "
        f"--no-sandbox runs it anyway, {UNCONFINED_COST}"
    )


def confined(mode: str = "auto", *, warn: bool = False) -> bool:
    """Does untrusted code run in the kernel sandbox here under ``mode``? ``required`` without
    a working sandbox raises :class:`UsageError` (:func:`refusal`); ``auto`` without one
    returns False, printing one warning a process where ``warn``."""
    global _warned
    chosen = _mode(mode)
    if chosen == "off":
        return False
    ok, why = kernel_sandbox.bwrap_available()
    if ok:
        return True
    if chosen == "required":
        raise UsageError(refusal(why))
    if warn and not _warned:
        _warned = True
        print(
            f"usar: warning: {why}; the mission runs without a kernel sandbox ({UNCONFINED_COST};"
            f" to get one, {_remedy()}; USAR_SANDBOX=off silences this)",
            file=sys.stderr,
        )
    return False
