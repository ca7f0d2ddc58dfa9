"""Where a batch's runs execute: a local pool of processes (default) or a Ray cluster.

Both engines call the same :func:`execute` for each run, which starts the run's own process
(``python -m usar_replay.batch.run_one``) in its own session and working directory, with its output
to ``<world>.output.txt``, and enforces the run's wall-clock limit. So the logs are the same
bytes whichever engine ran them, and a run's crash, hang or Ctrl-C is that process group's
affair: the engine kills the group (the recorder and the mission process) and goes on.

Ray is imported only by :class:`RayEngine` (``pip install 'usar-replay[ray]'``). On a cluster,
every node must see the submissions and output folders at the same paths (a shared file system)
and have usar-replay installed; see docs/batch.md.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from dataclasses import asdict
from pathlib import Path
from typing import Any, Protocol

from usar_replay.batch.plan import RunJob, RunResult, read_json
from usar_replay.batch.run_state import clean_environment
from usar_replay.core.errors import UsageError
from usar_replay.core.safe_text import safe_copy, team_lines
from usar_replay.sandbox import cpu_sets
from usar_replay.sandbox.run_folder import unmount_under

__all__ = ["Engine", "LocalEngine", "RayEngine", "execute", "make_engine", "share_cpus"]

GRACE_S = 60.0
"""Seconds a run may take to close its log after SIGTERM/SIGINT before its group is killed."""

_running: set[subprocess.Popen[bytes]] = set()
_lock = threading.Lock()
_stop = threading.Event()


def _kill_group(proc: subprocess.Popen[bytes]) -> None:
    """SIGKILL what is left of the run's process group (a mission process stuck in a loop)."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, signal.SIGKILL)


def _stop_run(proc: subprocess.Popen[bytes], sig: int) -> int:
    """Ask the run to stop (SIGTERM: wall limit, SIGINT: cut off), then force it."""
    with contextlib.suppress(ProcessLookupError):
        proc.send_signal(sig)
    try:
        return proc.wait(timeout=GRACE_S)
    except subprocess.TimeoutExpired:
        _kill_group(proc)
        return proc.wait()


def _tail(path: Path, lines: int = 20) -> str:
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return ""
    return "\n".join(team_lines(text.rstrip())[-lines:])  # the team's text: no CR starts a line


def execute(job_json: str) -> dict[str, Any]:
    """Run one job in its own process and return its :class:`RunResult` as a dict (plain data:
    it crosses Ray). Never raises for what the run did; KeyboardInterrupt stops the run."""
    job = RunJob.from_json(job_json)
    if _stop.is_set():
        return asdict(RunResult(job.team, job.world, "interrupted"))
    work = job.work_dir
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    output = work / "output.txt"
    env = clean_environment(os.environ)  # an engine's own variables left out (.run_state)
    env.update(TMPDIR=str(work), OMP_NUM_THREADS="1", PYTHONDONTWRITEBYTECODE="1")
    # a new file in a folder only usar writes (the run's sandbox gets a folder inside it)
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC
    with os.fdopen(os.open(output, flags, 0o666), "wb") as out:
        proc = subprocess.Popen(
            [sys.executable, "-m", "usar_replay.batch.run_one"],
            stdin=subprocess.PIPE,
            stdout=out,
            stderr=subprocess.STDOUT,
            cwd=work,
            env=env,
            start_new_session=True,  # its own process group: killed as one, no terminal Ctrl-C
        )
    with _lock:
        _running.add(proc)
    wall_limited = False
    try:
        assert proc.stdin is not None
        proc.stdin.write(job.to_json().encode())
        proc.stdin.close()
        try:
            code = proc.wait(timeout=job.run_limits.wall_s or None)
        except subprocess.TimeoutExpired:
            wall_limited = True
            code = _stop_run(proc, signal.SIGTERM)
    except KeyboardInterrupt:  # Ray's cancel, or Ctrl-C in the driver's thread
        _stop_run(proc, signal.SIGINT)
        raise
    finally:
        _kill_group(proc)
        with _lock:
            _running.discard(proc)
    tail = _tail(output)
    if output.exists():  # the team's text for people: its controls escaped (core/safe_text)
        shown = work / "output.safe.txt"
        safe_copy(output, shown)
        os.replace(shown, job.path(".output.txt"))
    unmount_under(str(work))  # a run killed at its limit left its folder's tmpfs mounted
    shutil.rmtree(work, ignore_errors=True)
    with contextlib.suppress(OSError):
        work.parent.rmdir()  # .work/ when it is empty
    if code == 0:
        grade = read_json(job.path(".grade.json")) or {}
        rec = read_json(job.path(".run.json")) or {}
        return asdict(RunResult.from_files(job.team, job.world, "graded", grade, rec))
    if code in (130, -signal.SIGINT) or (_stop.is_set() and not wall_limited):
        return asdict(RunResult(job.team, job.world, "interrupted"))
    why = f"the run's process exited with code {code}"
    if wall_limited:
        why = "the run did not stop within its wall-clock limit"
    return asdict(RunResult(job.team, job.world, "error", error=f"{why}\n{tail}".rstrip()))


def interrupt_all() -> None:
    """Ctrl-C: start no more runs and cut off the running ones (their logs are closed)."""
    _stop.set()
    with _lock:
        procs = list(_running)
    for p in procs:
        with contextlib.suppress(ProcessLookupError):
            p.send_signal(signal.SIGINT)


class Engine(Protocol):
    """Runs jobs, calling ``on_result`` in the caller's thread as each one ends."""

    def run(self, jobs: Sequence[RunJob], on_result: Callable[[RunResult], None]) -> None: ...


def share_cpus(jobs: int, free: int, usable: int) -> tuple[int, int]:
    """(runs at a time, CPUs per run) for ``--jobs`` on ``free`` CPUs no other usar run holds
    out of ``usable`` ones (0: no CPU sets here, nothing claimed). Each run gets a CPU set of its
    own (:mod:`usar_replay.sandbox.cpu_sets`), so a batch never runs more runs at once than there
    are free CPUs (one at a time, waiting for a set, when none is free now), and splits them
    evenly: on 2 CPUs ``--jobs 2`` is one each, ``--jobs 1`` two for the one run."""
    if usable <= 0:
        return jobs, 0
    slots = max(1, min(jobs, free))
    return slots, max(1, free // slots)


class LocalEngine:
    """``--jobs N`` runs at a time on this machine (threads that each wait on a run's process),
    no more than there are free CPUs (:func:`share_cpus`; :attr:`slots`)."""

    def __init__(self, jobs: int) -> None:
        if jobs < 1:
            raise UsageError(f"--jobs {jobs}: expected 1 or more")
        self.jobs = jobs
        free, usable = len(cpu_sets.free_cpus()), len(cpu_sets.usable_cpus())
        self.slots, self.cpus = share_cpus(jobs, free, usable)
        """Runs at a time and CPUs per run (0: no CPU sets on this machine)."""

    def run(self, jobs: Sequence[RunJob], on_result: Callable[[RunResult], None]) -> None:
        _stop.clear()
        if not jobs:
            return
        if self.cpus:  # each run's share, claimed by the run itself as it starts
            jobs = [j.with_cpus(self.cpus) for j in jobs]
        with ThreadPoolExecutor(max_workers=min(self.slots, len(jobs))) as pool:
            pending: set[Future[dict[str, Any]]] = {pool.submit(execute, j.to_json()) for j in jobs}
            try:
                while pending:
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for f in sorted(done, key=lambda f: id(f)):
                        on_result(RunResult(**f.result()))
            except KeyboardInterrupt:
                interrupt_all()
                for f in pending:
                    f.cancel()
                raise


class RayEngine:
    """Each run a Ray task (1 CPU) calling :func:`execute` on whichever node Ray picks.

    ``address``: an existing cluster (``ray://HOST:10001`` or ``auto``); without it, a Ray
    instance on this machine with ``jobs`` CPUs (or the one already initialised, as tests do).
    """

    def __init__(self, jobs: int, address: str | None = None) -> None:
        try:
            import ray
        except ImportError as err:
            raise UsageError(
                "--engine ray: Ray is not installed; pip install 'usar-replay[ray]'"
            ) from err
        self.ray = ray
        self.started = False
        if not ray.is_initialized():
            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
            if address:
                kwargs["address"] = address
            else:
                kwargs["num_cpus"] = max(1, jobs)
            ray.init(**kwargs)
            self.started = True

    def run(self, jobs: Sequence[RunJob], on_result: Callable[[RunResult], None]) -> None:
        ray = self.ray
        if not jobs:
            return
        task = ray.remote(num_cpus=1, max_retries=0)(execute)
        # one CPU set of one CPU per run, as Ray counts them (a run that took two when free
        # would make the next one on the node wait for its set)
        jobs = [j.with_cpus(1) for j in jobs]
        refs = {task.remote(j.to_json()): j for j in jobs}
        pending = list(refs)
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    job = refs[ref]
                    try:
                        result = RunResult(**ray.get(ref))
                    except Exception as err:  # noqa: BLE001 - a lost node is this run's error
                        result = RunResult(job.team, job.world, "error", error=f"Ray: {err}")
                    on_result(result)
        except KeyboardInterrupt:
            for ref in pending:
                with contextlib.suppress(Exception):
                    ray.cancel(ref)
            raise
        finally:
            if self.started:
                ray.shutdown()
                self.started = False


def make_engine(name: str, jobs: int, address: str | None = None) -> Engine:
    """``local`` or ``ray`` (imported only here, only when asked for)."""
    if name == "local":
        if address:
            raise UsageError("--address is for --engine ray")
        return LocalEngine(jobs)
    if name == "ray":
        return RayEngine(jobs, address)
    raise UsageError(f"--engine {name}: expected local or ray")
