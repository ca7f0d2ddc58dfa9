"""A team's files parsed as hostile data: bounded before any parser sees them.

Why: a team's folder is its submission, and every file in it is the team's to shape. A 5 KB
``usar.toml`` nested 5,000 tables deep makes ``tomllib`` raise ``RecursionError``; a 100 MB
``package.xml`` is read whole into memory by a plain ``read_text``; a launch file or a YAML
file nested thousands deep makes roslaunch (inside the run's sandbox) or a later walk over its
values recurse past Python's limit. Each of those stopped a whole class's batch, or ended a
run with a traceback instead of a verdict. Here every parser of a team's file goes through one
gate, in this order:

1. **size**, read before parsing: the file is opened without following a link, checked to be a
   regular file (``fstat``), and refused past its cap (:data:`MAX_CONFIG_BYTES` for
   ``usar.toml``, :data:`MAX_XML_BYTES`, :data:`MAX_YAML_BYTES`) without reading the rest;
2. **encoding**: UTF-8 (a BOM allowed), or for XML the encoding its declaration names;
3. **nesting depth**, at most :data:`MAX_DEPTH`: TOML's parsed tables and arrays (measured
   without recursion; a ``RecursionError`` inside ``tomllib`` is the same refusal), XML's
   elements (counted by expat as it streams, which also refuses ``<!ENTITY>`` declarations: a
   launch file needs none, and they are how an entity bomb is built), YAML's block and flow
   levels (counted line by line, without a YAML library: a pure-Python YAML parser takes
   seconds a megabyte, and PyYAML is not one of usar's dependencies).

A file that fails is :class:`~usar_replay.core.errors.TeamFileRefused` (an
:class:`~usar_replay.core.errors.UnusableSubmission`): one line naming the file and the rule,
which ``usar batch`` makes that team's verdict while every other team is graded, and ``usar
record`` prints as ``usar: error: ...``. What is within the bounds but wrong (a launch file's
syntax, a YAML typo) is left to the tool that reads it (roslaunch in the sandbox), whose
message the team gets as it always did.
"""

from __future__ import annotations

import codecs
import os
import re
import stat
import tomllib
import xml.parsers.expat
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from usar_replay.core.errors import TeamFileRefused, UnusableSubmission
from usar_replay.core.folder_walk import walk
from usar_replay.core.safe_text import safe_line

__all__ = [
    "MAX_CONFIG_BYTES",
    "MAX_DEPTH",
    "MAX_XML_BYTES",
    "MAX_YAML_BYTES",
    "PARSED_NAMES",
    "PARSED_SUFFIXES",
    "check_file",
    "check_package",
    "check_xml",
    "check_yaml",
    "head",
    "parsed",
    "read_bytes",
    "read_text",
    "toml",
    "toml_file",
]

MAX_CONFIG_BYTES = 256 * 1024
"""``usar.toml``: a few tables of a few lines (the same cap as the start's texts)."""
MAX_XML_BYTES = 2 * 1024 * 1024
"""A ``package.xml`` or launch file: the course's are a few kilobytes."""
MAX_YAML_BYTES = 2 * 1024 * 1024
"""A parameter file: the course's largest (``dwa_local_planner_params.yaml``) is 2 KB."""
MAX_HEAD_BYTES = 1024 * 1024
"""What :func:`head` reads of a file scanned for a word (a ``CMakeLists.txt``'s
``add_executable``): the course's are 8 KB."""
MAX_DEPTH = 64
"""Levels of tables, arrays, elements or YAML blocks: the course's files use fewer than 10."""

_CATKIN_OUTPUTS = frozenset({"build", "devel", "install", "logs", "__pycache__", ".git"})

PARSED_NAMES = ("package.xml", "usar.toml")
PARSED_SUFFIXES = (".launch", ".launch.xml", ".yaml", ".yml")
"""The files of a team's package that a parser reads (usar's, catkin's or roslaunch's): the
names above and these suffixes. Other XML and TOML (an OpenCV cascade, a ``pyproject.toml``)
is never parsed, so never refused."""


def parsed(name: str) -> bool:
    """Is a file of this name one a parser reads (:data:`PARSED_NAMES`, :data:`PARSED_SUFFIXES`)?"""
    return name in PARSED_NAMES or name.lower().endswith(PARSED_SUFFIXES)


def _refuse(label: str, why: str) -> TeamFileRefused:
    return TeamFileRefused(f"{safe_line(label)}: {why}")


def read_bytes(path: str | os.PathLike[str], limit: int, label: str = "") -> bytes:
    """The bytes of a team's file, at most ``limit`` of them: never through a link, a regular
    file only, its size checked on the opened descriptor before any byte is read (and again
    by reading one past the cap: a file growing as it is read). :class:`TeamFileRefused`
    for any of those."""
    label = label or Path(path).name
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as err:
        raise _refuse(label, f"cannot be read ({err.strerror})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise _refuse(label, "not a regular file")
        if st.st_size > limit:
            raise _refuse(label, f"{st.st_size} bytes; usar reads at most {limit} of this file")
        chunks: list[bytes] = []
        got = 0
        while got <= limit:
            block = os.read(fd, min(1 << 20, limit + 1 - got))
            if not block:
                break
            chunks.append(block)
            got += len(block)
    except OSError as err:
        raise _refuse(label, f"cannot be read ({err.strerror})") from None
    finally:
        os.close(fd)
    if got > limit:
        raise _refuse(label, f"over {limit} bytes; usar reads at most {limit} of this file")
    return b"".join(chunks)


def _utf8(data: bytes, label: str) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise _refuse(
            label,
            f"not UTF-8 text (byte 0x{data[err.start]:02x} at offset {err.start}); "
            "save it as UTF-8",
        ) from None


def read_text(path: str | os.PathLike[str], limit: int, label: str = "") -> str:
    """:func:`read_bytes` decoded as UTF-8 (:class:`TeamFileRefused` when it is not)."""
    label = label or Path(path).name
    return _utf8(read_bytes(path, limit, label), label)


def head(path: str | os.PathLike[str], limit: int = MAX_HEAD_BYTES) -> str:
    """The first ``limit`` bytes of a team's file as text (bytes that are not UTF-8 replaced),
    or '' for one :func:`read_bytes` refuses to open (a link, not a regular file): for a scan
    that looks for a word and never refuses a team (is there an ``add_executable``?), whatever
    the file's size."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return ""
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return ""
        chunks: list[bytes] = []
        got = 0
        while got < limit and (block := os.read(fd, min(1 << 20, limit - got))):
            chunks.append(block)
            got += len(block)
    except OSError:
        return ""
    finally:
        os.close(fd)
    return b"".join(chunks).decode("utf-8", errors="replace")


def _depth(value: Any) -> int:
    """How deep tables and arrays nest in a parsed value (1 for a flat table), measured with
    a stack of its own: the value may be as deep as the parser allowed."""
    deepest = 0
    stack: list[tuple[Any, int]] = [(value, 1)]
    while stack:
        item, level = stack.pop()
        if isinstance(item, dict):
            children: Iterable[Any] = item.values()
        elif isinstance(item, list):
            children = item
        else:
            continue
        deepest = max(deepest, level)
        if deepest > MAX_DEPTH:
            return deepest
        stack.extend((c, level + 1) for c in children)
    return deepest


def toml(text: str, label: str) -> dict[str, Any]:
    """A team's TOML text as a table: :class:`TeamFileRefused` (one line) for text that is not
    TOML or nests deeper than :data:`MAX_DEPTH` (inline tables and arrays make ``tomllib``
    recurse; dotted keys and headers nest without it)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise _refuse(label, f"not valid TOML: {err}") from None
    except RecursionError:
        raise _refuse(label, f"nested deeper than {MAX_DEPTH} levels") from None
    if _depth(data) > MAX_DEPTH:
        raise _refuse(label, f"nested deeper than {MAX_DEPTH} levels")
    return data


def toml_file(path: str | os.PathLike[str], label: str = "") -> dict[str, Any]:
    """A team's TOML file (``usar.toml``), bounded (:data:`MAX_CONFIG_BYTES`) and checked."""
    label = label or Path(path).name
    return toml(read_text(path, MAX_CONFIG_BYTES, label), label)


_XML_DECL = re.compile(rb"^\s*<\?xml[^>]*?encoding\s*=\s*[\"']([A-Za-z0-9._-]{1,40})[\"']")


def check_xml(data: bytes, label: str) -> None:
    """A team's XML (``package.xml``, a launch file) within the rules: its encoding (UTF-8, or
    the one its declaration names), elements nested at most :data:`MAX_DEPTH` deep, and no
    ``<!ENTITY>`` declaration. A syntax error ends the scan without a refusal: roslaunch and
    catkin say what it is, in the team's run."""
    m = _XML_DECL.match(data[:200])
    name = m.group(1).decode("ascii") if m else "utf-8"
    try:
        codec = codecs.lookup(name).name
    except LookupError:
        raise _refuse(label, f"declares an unknown encoding {name!r}; save it as UTF-8") from None
    if codec in ("utf-8", "utf-8-sig"):
        _utf8(data, label)
    else:
        try:
            data.decode(codec)
        except UnicodeDecodeError as err:
            raise _refuse(label, f"not {name} text as it declares (offset {err.start})") from None
    parser = xml.parsers.expat.ParserCreate()
    level = 0

    def start(_name: str, _attrs: Any) -> None:  # a refusal raised here ends expat's parse
        nonlocal level
        level += 1
        if level > MAX_DEPTH:
            raise _refuse(label, f"elements nested deeper than {MAX_DEPTH} levels")

    def end(_name: str) -> None:
        nonlocal level
        level -= 1

    def entity(*_args: Any) -> None:
        raise _refuse(label, "declares an <!ENTITY>; a launch file or package.xml needs none")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.EntityDeclHandler = entity
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError:
        return  # the team's syntax: its tools say what it is


_FLOW = re.compile(r"""'[^']*'|"(?:[^"\\]|\\.)*"|[\[\]{}]|\s#.*$""")


def _yaml_depth(text: str) -> int:
    """How deep a YAML text's blocks and flow collections nest, counted line by line: each
    indentation deeper than the last open one opens a level, each leading ``- `` one more,
    each ``[``/``{`` outside quotes one more (closed by ``]``/``}``). An upper bound of what a
    YAML parser builds (a block scalar's lines count as a level), never a parse."""
    indents: list[int] = []
    flow = 0
    deepest = 0
    for line in text.split("\n"):
        body = line.lstrip(" ")
        if not body.strip() or body.startswith("#"):
            continue
        if flow == 0:
            indent = len(line) - len(body)
            while indents and indents[-1] >= indent:
                indents.pop()
            indents.append(indent)
            dashes = len(body) - len(body.lstrip("- ")) if body.startswith("- ") else 0
            block = len(indents) + body[:dashes].count("-")
        else:
            block = len(indents)
        for token in _FLOW.findall(body):
            if token in ("[", "{"):
                flow += 1
            elif token in ("]", "}"):
                flow = max(0, flow - 1)
            deepest = max(deepest, block + flow)
            if deepest > MAX_DEPTH:
                return deepest
        deepest = max(deepest, block + flow)
        if deepest > MAX_DEPTH:
            return deepest
    return deepest


def check_yaml(data: bytes, label: str) -> None:
    """A team's YAML (a parameter file roslaunch loads) within the rules: UTF-8, blocks and
    flow collections nested at most :data:`MAX_DEPTH` deep (:func:`_yaml_depth`)."""
    if _yaml_depth(_utf8(data, label)) > MAX_DEPTH:
        raise _refuse(label, f"nested deeper than {MAX_DEPTH} levels")


def check_file(path: str | os.PathLike[str], label: str = "") -> None:
    """One of a team's files by its name (XML: ``.launch``, ``.xml``; YAML: ``.yaml``,
    ``.yml``; TOML: ``.toml``), read bounded and checked: :class:`TeamFileRefused` with one
    line when it breaks a rule."""
    label = label or Path(path).name
    suffix = Path(path).suffix.lower()
    if suffix in (".launch", ".xml"):
        check_xml(read_bytes(path, MAX_XML_BYTES, label), label)
    elif suffix in (".yaml", ".yml"):
        check_yaml(read_bytes(path, MAX_YAML_BYTES, label), label)
    elif suffix == ".toml":
        toml_file(path, label)
    else:
        raise ValueError(f"{path}: not a kind of file usar parses")


def check_package(folder: str | os.PathLike[str], what: str = "the team's folder") -> None:
    """Every file of ``folder`` a parser reads (``usar.toml``, ``package.xml``, launch files,
    YAML: :func:`parsed`) within the rules, before usar or roslaunch parses any:
    :class:`TeamFileRefused` (one line) at the first that is not. The folder is walked by
    :func:`usar_replay.core.folder_walk.walk`'s rules (no link followed, caps on files and
    bytes); catkin's outputs are left out. A folder past the walk's own caps is not refused
    here: the build walks it by the same rules and makes that the run's ``build_failed``, in a
    closed log, as a batch's digest makes it ``bad_submission``."""
    try:
        entries = walk(folder, what=what, skip_dirs=_CATKIN_OUTPUTS)
    except TeamFileRefused:
        raise
    except UnusableSubmission:
        return
    for entry in entries:
        rel = entry.rel_path
        if entry.link is None and parsed(rel.name):
            check_file(entry.path, rel.as_posix())
