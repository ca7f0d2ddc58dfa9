"""Where a view goes and the ``rerun`` viewer process that shows it.

Why a module of its own: starting, finding and stopping the viewer (a native window or the web
viewer's two servers, bound to one address) is process management with its own failure modes
(no display, a stale ``DISPLAY``, ports taken), unrelated to turning a log into rerun columns
(:mod:`usar_replay.viewer.view`). Imports no rerun: the viewer is the ``rerun`` command of this
environment, run as a child process.

* :class:`Output` and :func:`choose_output`: an ``.rrd`` file, the native viewer, or the web
  viewer (the CLI's rule);
* :class:`ViewerProcess`: the viewer started as a child that binds its ports to ``--bind``; a
  viewer that cannot open a window exits within a fraction of a second and that exit is
  watched for, so falling back to a file is quick.
"""

from __future__ import annotations

import contextlib
import ipaddress
import os
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO
from urllib.parse import quote

from usar_replay.core.errors import UsageError
from usar_replay.core.outfiles import check_output

__all__ = [
    "DEFAULT_BIND",
    "Output",
    "ViewerProcess",
    "check_rrd",
    "choose_output",
    "default_rrd_path",
    "open_command",
]

DEFAULT_BIND = "127.0.0.1"
VIEWER_START_S = 10.0
"""How long a starting viewer may take to listen on its ports."""
VIEWER_SETTLE_S = 1.0
"""A native viewer that cannot open its window starts its server, then exits (measured: 0.02 s
later); one that is still running this long after listening is taken as up."""


@dataclass(frozen=True, slots=True)
class Output:
    """Where a view goes: a native viewer, an ``.rrd`` file, the web viewer (file and web mix)."""

    spawn: bool = False
    rrd: Path | None = None
    web: bool = False


def default_rrd_path(log_path: str | os.PathLike[str]) -> Path:
    """Next to the recording, same stem: ``runs/course.mcap`` -> ``runs/course.rrd``."""
    return Path(log_path).with_suffix(".rrd")


def choose_output(
    log_path: str | os.PathLike[str],
    *,
    save: str | os.PathLike[str] | None,
    web: bool,
    env: Mapping[str, str],
) -> Output:
    """The CLI's rule: ``--save`` writes a file; ``--web`` serves; else a display spawns the
    native viewer and no display writes the file next to the recording (so a headless machine
    still produces something to open elsewhere)."""
    rrd = Path(save) if save is not None else None
    if web:
        return Output(rrd=rrd, web=True)
    if rrd is not None:
        return Output(rrd=rrd)
    if env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"):
        return Output(spawn=True)
    return Output(rrd=default_rrd_path(log_path))


def check_rrd(rrd: Path, log: Path, *, overwrite: bool, option: str = "--save") -> None:
    """An ``.rrd`` output may not be the log, a directory, or (without ``overwrite``) a file
    that exists (:func:`usar_replay.core.outfiles.check_output`; raises ``UsageError``, exit 2)."""
    check_output(rrd, overwrite=overwrite, inputs=[log], option=option)


def _rerun_executable() -> str | None:
    """The ``rerun`` CLI of this environment (the one that matches this SDK's file format)."""
    sibling = Path(sys.executable).parent / "rerun"
    found = shutil.which("rerun")
    if found and (not sibling.exists() or Path(found).resolve() == sibling.resolve()):
        return "rerun"
    return str(sibling) if sibling.exists() else found


def _rerun_binary() -> str | None:
    """The viewer binary itself, for starting it as a child process: the ``rerun`` command is a
    Python wrapper that runs this binary as *its* child, so stopping the wrapper would leave
    the binary running (and its ports taken)."""
    import importlib.util

    spec = importlib.util.find_spec("rerun_cli")
    if spec is not None and spec.origin is not None:
        binary = Path(spec.origin).parent / "rerun"
        if binary.is_file() and os.access(binary, os.X_OK):
            return str(binary)
    return _rerun_executable()


def open_command(rrd: str | os.PathLike[str]) -> str:
    """The exact shell command that opens ``rrd`` in the viewer (``rerun PATH``)."""
    exe = _rerun_executable() or "rerun"
    return f"{shlex.quote(exe)} {shlex.quote(str(rrd))}"


def _port_open(host: str, port: int) -> bool:
    try:
        with socket.create_connection((host, port), timeout=0.5):
            return True
    except OSError:
        return False


def _local_host(bind: str) -> str:
    """Where this machine reaches a server bound to ``bind`` (loopback for 'all interfaces')."""
    try:
        if ipaddress.ip_address(bind).is_unspecified:
            return "127.0.0.1"
    except ValueError:
        pass
    return bind


def _url_host(host: str) -> str:
    return f"[{host}]" if ":" in host else host


@dataclass(slots=True)
class ViewerProcess:
    """A ``rerun`` viewer (native, or the web viewer's server) this command started or found.

    Both ports of the web viewer (the page and its gRPC data) are bound to the same ``bind``
    address by the ``rerun`` command itself, so they are reachable from the same places.
    """

    grpc_url: str
    """Where this process sends the recording (``rerun+http://HOST:PORT/proxy``)."""
    proc: subprocess.Popen[bytes] | None = None
    """None when a viewer was already listening on the port (it is not ours to stop)."""
    web_url: str | None = None

    @classmethod
    def start(cls, *, web: bool, bind: str, grpc_port: int, web_port: int) -> ViewerProcess:
        """Start the native viewer (``web`` False) or the web viewer, and wait until it
        listens. Raises :class:`UsageError` when it cannot start, saying why in one line."""
        exe = _rerun_binary()
        if exe is None:
            raise UsageError("the `rerun` command is not installed; use --save OUT.rrd")
        host = _local_host(bind)
        grpc_url = f"rerun+http://{_url_host(host)}:{grpc_port}/proxy"
        if not web and _port_open(host, grpc_port):
            return cls(grpc_url)  # a viewer is already open there: use it, as rerun does
        wanted = [(grpc_port, "--grpc-port"), *([(web_port, "--web-port")] if web else [])]
        for port, option in wanted:
            if _port_open(host, port):
                raise UsageError(f"port {port} is in use; pick another with {option} N")
        args = [exe, "--bind", bind, "--port", str(grpc_port)]
        if web:
            args += ["--serve-web", "--web-viewer-port", str(web_port)]
            args += ["--server-memory-limit", "50%"]
        else:
            args += ["--hide-welcome-screen", "--memory-limit", "75%"]
        errors: IO[bytes] = tempfile.TemporaryFile()  # noqa: SIM115 - kept by the child
        env = {**os.environ, "RUST_LOG": os.environ.get("RUST_LOG", "warn")}
        try:
            proc = subprocess.Popen(
                args,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=errors,
                env=env,
                start_new_session=True,  # the native viewer outlives this command; the web
                # server is stopped as a group (stop()), whatever children it has
            )
        except OSError as err:
            errors.close()
            raise UsageError(f"cannot start `{exe}`: {err.strerror or err}") from err
        ports = [grpc_port, web_port] if web else [grpc_port]
        problem = _wait_listening(proc, host, ports, settle=not web)
        if problem is not None:
            errors.seek(0)
            why = _last_error(errors.read().decode("utf-8", "replace")) or problem
            errors.close()
            raise UsageError(f"the rerun viewer did not start: {why}")
        errors.close()
        web_url = None
        if web:
            shown = _shown_host(bind)
            data = f"rerun+http://{_url_host(shown)}:{grpc_port}/proxy"
            web_url = f"http://{_url_host(shown)}:{web_port}/?url={quote(data, safe=':/')}"
        return cls(grpc_url, proc, web_url)

    def stop(self) -> None:
        """Stop a web viewer's server (a native viewer is the user's to close)."""
        if self.proc is None or self.web_url is None or self.proc.poll() is not None:
            return
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.proc.pid, signal.SIGTERM)
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()


def _shown_host(bind: str) -> str:
    """The name a browser uses for a server bound to ``bind``: ``localhost`` for loopback, this
    machine's name when it listens on every interface (a remote browser needs it)."""
    ip = ipaddress.ip_address(bind)
    if ip.is_loopback:
        return "localhost"
    return socket.gethostname() if ip.is_unspecified else bind


def _wait_listening(
    proc: subprocess.Popen[bytes], host: str, ports: Sequence[int], *, settle: bool
) -> str | None:
    """None once ``proc`` listens on every port (and, with ``settle``, is still running
    :data:`VIEWER_SETTLE_S` later); else what went wrong. Returns as soon as it exits."""
    deadline = time.monotonic() + VIEWER_START_S
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            return f"it exited with code {proc.returncode}"
        if all(_port_open(host, p) for p in ports):
            if not settle:
                return None
            try:
                proc.wait(timeout=VIEWER_SETTLE_S)
            except subprocess.TimeoutExpired:
                return None
            return f"it exited with code {proc.returncode}"
        time.sleep(0.05)
    proc.kill()
    proc.wait()
    return f"it did not listen within {VIEWER_START_S:.0f} s"


def _last_error(text: str) -> str:
    """The viewer's own reason, e.g. ``Failed to open connection to X server``."""
    for line in reversed(text.strip().splitlines()):
        if "Error" in line or "error" in line:
            reason = line.split(": ")[-1].strip()
            return reason[:120]
    return ""
