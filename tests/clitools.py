"""Test helpers that run the `usar` command as a user does: a subprocess, its exit code, stderr."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path


def usar(
    *args: str,
    cwd: str | os.PathLike[str] | None = None,
    env: dict[str, str] | None = None,
    timeout: float | None = None,
) -> subprocess.CompletedProcess[str]:
    """``usar ARGS...`` in a fresh interpreter (what a shell user sees, tracebacks included),
    in ``cwd`` when given (the package must then be importable from the environment), with
    ``env`` as its environment when given."""
    if cwd is not None:  # the tests may import the package from the checkout, not an install
        root = str(Path(__file__).resolve().parents[1])
        base = env if env is not None else dict(os.environ)
        env = {
            **base,
            "PYTHONPATH": os.pathsep.join(p for p in (root, base.get("PYTHONPATH", "")) if p),
        }
    return subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", *args],
        capture_output=True,
        text=True,
        check=False,
        cwd=cwd,
        env=env,
        timeout=timeout,
    )


def start_usar(*args: str, env: dict[str, str] | None = None) -> subprocess.Popen[str]:
    """``usar ARGS...`` started in the background, stdout and stderr piped, with the default
    signal handlers (:func:`default_signals`), so a test can signal it while it runs."""
    return subprocess.Popen(
        [sys.executable, "-m", "usar_replay.cli", *args],
        preexec_fn=default_signals,  # only resets handlers: safe before exec
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def no_display() -> dict[str, str]:
    """The environment without a display: ``usar view`` then saves or says how to open."""
    return {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}


def one_error_line(out: subprocess.CompletedProcess[str], code: int, *needles: str) -> None:
    """The user-error contract: exit ``code``, one ``usar: error:`` line naming ``needles``."""
    assert out.returncode == code, out.stderr
    assert "Traceback" not in out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("usar: error: "), out.stderr
    for n in needles:
        assert n in lines[0], lines[0]


def default_signals() -> None:
    """``preexec_fn`` for a child that a test interrupts: SIGINT, SIGTERM and SIGHUP as a
    terminal delivers them, whatever this test run inherited (a runner started in the
    background has SIGINT ignored, and usar, like any Unix program, keeps an inherited ignore)."""
    import signal

    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, signal.SIG_DFL)


def run_batch(subs: Path, room: Path, out: Path, *extra: str) -> tuple[int, str]:
    """``usar batch SUBS --scenario ROOM -o OUT EXTRA...`` in this process: its exit code and
    what it printed (the batch's engines start their own processes)."""
    import io

    from usar_replay.cli import main as cli

    buf = io.StringIO()
    old = sys.stdout
    sys.stdout = buf
    try:
        code = cli.main(["batch", str(subs), "--scenario", str(room), "-o", str(out), *extra])
    finally:
        sys.stdout = old
    return code, buf.getvalue()
