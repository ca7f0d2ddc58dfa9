"""ROS 1 message definitions from untrusted hands: their shape checked in one linear pass, each
parsed once, and a run's (or a log's) definitions together within budgets.

Why: a definition (the ``message_definition`` a node sends, or a ``ros1msg`` schema in a log) is
text a student's package wrote, and reading it with rosbags is far from free: its parser, its
typestore's ``register`` (a dataclass per type) and its generated (de)serializers cost about
0.5 ms per field and 3 ms per type, more than linearly in the fields of one type. Measured
(``tests/core/test_ros1defs.py`` keeps the shapes): one type of 20,000 ``int32`` fields, 249 KB,
under the old 256 KiB cap, took 16.7 s of the root recorder's CPU; 2,200 chained types ended in
a ``RecursionError``; an 8 MB definition in a log kept ``usar echo`` busy past a minute. The
course's largest types are far smaller (``nav_msgs/GetMapActionResult``: 4.7 KB, 10 types, 39
fields), so these caps (:class:`DefinitionLimits`, defaults in the README's "Damaged logs") bound
the work a definition can cause to a fraction of a second, and a run's definitions together to
about a second, whatever their text:

* per definition: its bytes, its types (``MSG:`` sections), its fields and constants, and how
  deep its types nest (a type that contains itself is refused: it has no finite message);
* per run (or per log read): the distinct definitions' bytes, types and fields together.

:func:`shape` checks one definition without rosbags, in one pass over its lines; only what
passes is parsed. :class:`Definitions` holds a run's parsed definitions (each parsed once, so a
topic's every message costs a dictionary lookup) and its totals. Refusals are
:class:`DefinitionRefused`, one sentence for a person: the recorder makes it the run's
``refused`` verdict, a reader of a log its one-line error.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from usar_replay.core.errors import DefinitionRefused

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = [
    "DefinitionLimits",
    "DefinitionRefused",
    "Definitions",
    "Shape",
    "shape",
]


@dataclass(frozen=True, slots=True)
class DefinitionLimits:
    """What one definition, and all of a run's together, may hold (see the module doc)."""

    max_bytes: int = 64 * 1024
    """One definition's UTF-8 bytes (64 KiB; the course's largest is 4.7 KB)."""
    max_types: int = 64
    """Types in one definition: the main type and its ``MSG:`` sections."""
    max_fields: int = 256
    """Fields and constants of all its types together (the course's largest: 39)."""
    max_depth: int = 32
    """How deep its types nest (``Odometry`` -> ``PoseWithCovariance`` -> ``Pose`` ->
    ``Point``: 3)."""
    run_bytes: int = 512 * 1024
    """The distinct definitions of one run (or one log read), bytes together."""
    run_types: int = 128
    """... types together."""
    run_fields: int = 1024
    """... fields and constants together (measured: 4 definitions of 250 fields, parsed and
    each message decoded, 0.5 s of CPU; the course's packages need a few dozen)."""


@dataclass(frozen=True, slots=True)
class Shape:
    """What :func:`shape` counted."""

    bytes: int
    types: int
    fields: int
    depth: int


_PRIMITIVES = frozenset(
    {"bool", "byte", "char", "float32", "float64", "string", "time", "duration"}
    | {f"{u}int{n}" for u in ("", "u") for n in (8, 16, 32, 64)}
)


def _short(name: str) -> str:
    """A type's name as a person reads it (``pkg/Type``, even when given ``pkg/msg/Type``), cut
    to 60 characters: it is the student's text and goes into a verdict's one line."""
    name = name.replace("/msg/", "/")
    return name if len(name) <= 60 else name[:57] + "..."


def shape(msgtype: str, definition: str, limits: DefinitionLimits | None = None) -> Shape:
    """Count the definition's bytes, types, fields and nesting in one pass over its lines;
    :class:`DefinitionRefused` at the first cap passed (before any more of it is read)."""
    lim = limits or DefinitionLimits()
    who = _short(msgtype)
    size = len(definition.encode("utf-8", errors="replace"))
    if size > lim.max_bytes:
        raise DefinitionRefused(
            f"the definition of {who} is {size:,} bytes; a definition is at most {lim.max_bytes:,}"
        )
    main = msgtype.replace("/msg/", "/")
    refs: dict[str, set[str]] = {main: set()}
    current, fields = main, 0
    for raw in definition.splitlines():
        line = raw.strip()
        if not line or line.startswith("#") or line.strip("=") == "":
            continue
        if line.startswith("MSG:"):
            current = line[4:].strip().replace("/msg/", "/")
            refs.setdefault(current, set())
            if len(refs) > lim.max_types:
                raise DefinitionRefused(
                    f"the definition of {who} holds more than {lim.max_types} types"
                )
            continue
        fields += 1
        if fields > lim.max_fields:
            raise DefinitionRefused(
                f"the definition of {who} holds more than {lim.max_fields} fields"
            )
        base = line.split(None, 1)[0].split("[", 1)[0]
        if base in _PRIMITIVES or "=" in base:
            continue
        if base == "Header":
            base = "std_msgs/Header"
        elif "/" not in base:
            base = f"{current.partition('/')[0]}/{base}"
        refs[current].add(base.replace("/msg/", "/"))
    depth = _depth(main, refs, lim.max_depth, who)
    return Shape(size, len(refs), fields, depth)


def _depth(main: str, refs: dict[str, set[str]], limit: int, who: str) -> int:
    """How deep the types under ``main`` nest (types not defined in the text count as
    leaves: rosbags refuses them later); :class:`DefinitionRefused` for a cycle or past
    ``limit``. Iterative: a chain of thousands of types must not exhaust Python's stack."""
    done: dict[str, int] = {}
    on_path: set[str] = set()
    stack: list[tuple[str, list[str]]] = [(main, sorted(refs.get(main, ())))]
    on_path.add(main)
    while stack:
        name, todo = stack[-1]
        if todo:
            child = todo.pop()
            if child in on_path:
                raise DefinitionRefused(f"the definition of {who}: {_short(child)} contains itself")
            if child not in done and child in refs:
                if len(stack) >= limit:
                    raise DefinitionRefused(
                        f"the definition of {who} nests types more than {limit} deep"
                    )
                on_path.add(child)
                stack.append((child, sorted(refs[child])))
            continue
        stack.pop()
        on_path.discard(name)
        done[name] = 1 + max((done.get(c, 0) for c in refs[name]), default=-1)
    return done[main]


class Definitions:
    """The parsed definitions of one run (the recorder's side) or one log read (``usar
    echo``): each (type, definition) parsed once, all of them within the run's budgets."""

    def __init__(self, limits: DefinitionLimits | None = None) -> None:
        self.limits = limits or DefinitionLimits()
        self._stores: dict[tuple[str, str], Typestore] = {}
        self.bytes = 0
        self.types = 0
        self.fields = 0

    def store(self, msgtype: str, definition: str) -> Typestore:
        """rosbags' typestore holding ``msgtype`` (a fresh one per definition: two packages'
        ``Header`` never meet); :class:`DefinitionRefused` past a cap, rosbags' errors when
        the text does not parse."""
        key = (msgtype, definition)
        found = self._stores.get(key)
        if found is not None:
            return found
        got = shape(msgtype, definition, self.limits)
        lim = self.limits
        if (
            self.bytes + got.bytes > lim.run_bytes
            or self.types + got.types > lim.run_types
            or self.fields + got.fields > lim.run_fields
        ):
            raise DefinitionRefused(
                f"the definition of {_short(msgtype)} is one too many: a run's ROS 1 "
                f"definitions hold at most {lim.run_bytes:,} bytes, {lim.run_types} types and "
                f"{lim.run_fields} fields together"
            )
        # counted before parsing: a definition that fails to parse still cost its parse
        self.bytes += got.bytes
        self.types += got.types
        self.fields += got.fields
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        store = get_typestore(Stores.EMPTY)
        store.register(get_types_from_msg(definition, msgtype))
        self._stores[key] = store
        return store

    def decode(self, msgtype: str, definition: str, data: bytes) -> Any:
        """The message as rosbags' value (a dataclass; arrays of numbers as numpy arrays).
        Raises :class:`DefinitionRefused`, or rosbags' errors (``ValueError`` and others) when
        the definition does not parse or the bytes are not a whole message of it."""
        name = msgtype if "/msg/" in msgtype else "{0}/msg/{2}".format(*msgtype.partition("/"))
        # rosbags refuses bytes left over (a message of another type) as a size mismatch
        return self.store(msgtype, definition).deserialize_ros1(bytes(data), name)
