"""core/signals: SIGINT, SIGTERM and SIGHUP, raised for real in this process, unwind a block
once as :class:`Terminated`; later ones are swallowed while it cleans up."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator

import pytest

from usar_replay.core.signals import HANDLED, Terminated, exit_code, handled


@pytest.fixture(autouse=True)
def _restore_handlers() -> Iterator[None]:
    before = {s: signal.getsignal(s) for s in HANDLED}
    # a test run started in the background (`&`, nohup) inherits ignored signals, which
    # handled() rightly leaves ignored: these tests want them as a terminal delivers them
    for s in HANDLED:
        if before[s] is signal.SIG_IGN:
            signal.signal(s, signal.default_int_handler if s == signal.SIGINT else signal.SIG_DFL)
    yield
    for s, h in before.items():
        signal.signal(s, h)


@pytest.mark.parametrize(
    ("signum", "text", "code"),
    [
        (signal.SIGINT, "interrupted by the user (Ctrl-C)", 130),
        (signal.SIGTERM, "terminated by SIGTERM", 143),
        (signal.SIGHUP, "terminated by SIGHUP", 129),
    ],
)
def test_each_signal_is_one_exception_with_its_exit_code(
    signum: signal.Signals, text: str, code: int
) -> None:
    with pytest.raises(Terminated) as caught, handled():
        signal.raise_signal(signum)
    assert str(caught.value) == text and caught.value.signum == signum
    assert isinstance(caught.value, KeyboardInterrupt)
    assert exit_code(caught.value) == code


def test_a_second_signal_during_cleanup_is_swallowed() -> None:
    cleaned = False
    with pytest.raises(Terminated), handled():
        try:
            signal.raise_signal(signal.SIGTERM)
        finally:
            signal.raise_signal(signal.SIGINT)  # a second Ctrl-C while closing the log
            cleaned = True
    assert cleaned
    signal.raise_signal(signal.SIGINT)  # still swallowed after the block: the command ends


def test_without_a_signal_the_previous_handlers_come_back() -> None:
    before = signal.getsignal(signal.SIGTERM)
    with handled():
        assert signal.getsignal(signal.SIGTERM) is not before
    assert signal.getsignal(signal.SIGTERM) is before
    assert exit_code(KeyboardInterrupt()) == 130


def test_an_ignored_sighup_stays_ignored() -> None:
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    with handled():
        assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
        signal.raise_signal(signal.SIGHUP)  # nohup: nothing happens


def test_outside_the_main_thread_nothing_is_set() -> None:
    seen: list[object] = []

    def run() -> None:
        with handled():
            seen.append(signal.getsignal(signal.SIGTERM))

    before = signal.getsignal(signal.SIGTERM)
    t = threading.Thread(target=run)
    t.start()
    t.join()
    assert seen == [before]
