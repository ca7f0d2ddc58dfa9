"""Writing output files safely: never over an input, never over a file without ``--overwrite``,
never a half-written file at the final name.

Why one module: every command that writes (record, scenario, grade's JSON/JUnit/CSV, view's
``.rrd``, report's HTML) must keep the same promises, and a promise kept in five places is broken
in one. Outputs are written to a temporary name beside the final one and renamed atomically when
complete; a failure (a full disk, Ctrl-C) removes the temporary file and leaves whatever was at
the final name untouched. The temporary file is created new (``O_EXCL|O_NOFOLLOW``) and renamed
over the final name, so a link found at either name is replaced, never written through (a batch
runs as root: docs/batch.md's threat model).
"""

from __future__ import annotations

import contextlib
import errno
import os
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any

from usar_replay.core.errors import UsageError

__all__ = ["atomic_output", "check_output", "write_bytes", "write_text"]


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve() or (a.exists() and b.exists() and a.samefile(b))
    except OSError:
        return False


def check_output(
    path: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    inputs: Iterable[str | os.PathLike[str]] = (),
    option: str = "",
) -> Path:
    """Refuse an output that is an input, a directory, or (without ``overwrite``) exists.

    ``option`` names the flag in the message (``--json``). Returns the path. Raises
    :class:`UsageError` (exit 2) with what to do.
    """
    p = Path(path)
    what = f"{option} {p}" if option else str(p)
    for i in inputs:
        if _same_file(p, Path(i)):
            raise UsageError(f"{what}: is an input of this command; choose another output path")
    if p.is_dir():
        raise UsageError(f"{what}: is a directory; give a file name")
    if p.exists() and not overwrite:
        raise UsageError(f"{what}: exists; pass --overwrite to replace it, or choose another path")
    parent = p.parent if str(p.parent) else Path(".")
    if parent.exists() and not parent.is_dir():
        raise UsageError(f"{what}: {parent} is not a directory")
    return p


def _os_error(p: Path, err: OSError) -> UsageError:
    if err.errno == errno.ENOSPC:
        return UsageError(f"{p}: the disk is full; free some space and run again")
    if err.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return UsageError(f"{p}: cannot write here (permission denied); choose another path")
    return UsageError(f"{p}: cannot write: {err.strerror or err}")


@contextlib.contextmanager
def atomic_output(
    path: str | os.PathLike[str],
    *,
    binary: bool = False,
    overwrite: bool = False,
    inputs: Iterable[str | os.PathLike[str]] = (),
    option: str = "",
) -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; on success it replaces ``path`` atomically.

    Checks the output first (:func:`check_output`). On any error the temporary file is removed
    and ``path`` is left as it was; an ``OSError`` (disk full, permissions) becomes a one-line
    :class:`UsageError`.
    """
    p = check_output(path, overwrite=overwrite, inputs=inputs, option=option)
    tmp = p.with_name(f".{p.name}.{os.getpid()}.tmp")
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()  # a cut-off write's, or a link planted there: removed, never followed
        fd = os.open(
            tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666
        )
        f = os.fdopen(fd, "wb" if binary else "w", encoding=None if binary else "utf-8")
    except OSError as err:
        raise _os_error(p, err) from err
    try:
        with f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        if p.exists() and not overwrite:  # appeared while we wrote: never replace it silently
            raise UsageError(f"{p}: appeared while this command ran; it was left as it is")
        os.replace(tmp, p)
    except OSError as err:
        raise _os_error(p, err) from err
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def write_text(path: str | os.PathLike[str], text: str, **kwargs: Any) -> Path:
    """Write ``text`` atomically (see :func:`atomic_output` for the keyword arguments)."""
    with atomic_output(path, **kwargs) as f:
        f.write(text)
    return Path(path)


def write_bytes(path: str | os.PathLike[str], data: bytes, **kwargs: Any) -> Path:
    """Write ``data`` atomically (see :func:`atomic_output` for the keyword arguments)."""
    with atomic_output(path, binary=True, **kwargs) as f:
        f.write(data)
    return Path(path)
