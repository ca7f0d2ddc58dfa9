"""SIGINT, SIGTERM and SIGHUP end a command the same way: an exception that unwinds it.

Why: a recording must be closed (summary, indexes, ``interrupted``) whether it is stopped by
Ctrl-C, ``kill`` (SIGTERM) or a closed terminal (SIGHUP); Python's default for the last two is
to die on the spot, leaving only a ``.part``. And a second Ctrl-C while the first is being handled
must not break the cleanup (a half-closed file, ``Exception ignored ... KeyboardInterrupt``): once
one signal has been turned into an exception, later ones are swallowed.

The exception is :class:`Terminated`, a :class:`KeyboardInterrupt`, so every ``except
KeyboardInterrupt`` / ``finally`` that already closes things does so for all three signals; its
text names the signal (``terminated by SIGTERM``) and :func:`exit_code` gives the shell's code
(128 + the signal's number: 130, 143, 129).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType

__all__ = ["HANDLED", "Terminated", "exit_code", "handled"]

HANDLED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class Terminated(KeyboardInterrupt):
    """A handled signal arrived; ``signum`` says which."""

    def __init__(self, signum: int) -> None:
        name = signal.Signals(signum).name
        text = (
            "interrupted by the user (Ctrl-C)"
            if signum == signal.SIGINT
            else f"terminated by {name}"
        )
        super().__init__(text)
        self.signum = signum


def exit_code(err: BaseException) -> int:
    """The process exit code for an interrupt: 128 + the signal (130 for a plain Ctrl-C)."""
    return 128 + (err.signum if isinstance(err, Terminated) else int(signal.SIGINT))


def _swallow(signum: int, frame: FrameType | None) -> None:
    """Later signals while the first is being handled: ignored (the command is ending)."""


def _raise(signum: int, frame: FrameType | None) -> None:
    for s in HANDLED:
        signal.signal(s, _swallow)
    raise Terminated(signum)


@contextlib.contextmanager
def handled() -> Iterator[None]:
    """Within the block, SIGINT/SIGTERM/SIGHUP raise :class:`Terminated` once; the previous
    handlers are restored after it, unless a signal came (the process is ending: later ones
    stay swallowed). Outside the main thread it does nothing (Python only lets
    the main thread set handlers)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in HANDLED}
    for s in HANDLED:
        if previous[s] is not signal.SIG_IGN:  # nohup's ignored SIGHUP stays ignored
            signal.signal(s, _raise)
    try:
        yield
    finally:
        if signal.getsignal(signal.SIGINT) is not _swallow:  # after a signal: keep swallowing
            for s, h in previous.items():
                signal.signal(s, h)
