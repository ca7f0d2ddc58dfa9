"""Fast CDR decoding: bytes straight to :mod:`usar_replay.core.msgs` values, one generated function
per message type.

Why: decoding is most of what ``usar grade`` and replay spend their time on. rosbags decodes
into its own objects (numpy arrays for every array field) that :mod:`usar_replay.core.cdr` then
converts to ours, and a frozen dataclass's keyword ``__init__`` costs about three times what
setting its slots directly does. The functions generated here read a message's bytes with
:mod:`struct` (consecutive fields whose alignment is known when the code is generated are read
by one ``unpack_from``) and fill each value's slots directly, so they build the same values,
of the same classes, as the rosbags path, several times faster.

rosbags stays the reference: a function here only decodes little-endian CDR that it can decode
completely and that passes every check rosbags makes (string lengths and terminators, sequence
lengths, the size of the message). Anything else raises :class:`Unsupported`, and the caller
decodes with rosbags, which gives its own value or error. The tests compare both paths on random
messages of every type and on damaged bytes.

The layout follows ROS 2's CDR (XCDR1, as rosbags writes it): a 4-byte encapsulation header,
then fields in order, each primitive aligned to its size counted from the end of that header;
a string is a ``uint32`` length (terminator included), the bytes and a NUL; a sequence is a
``uint32`` count followed by its elements (a primitive sequence is aligned to its element size
only when it is not empty); fixed-size arrays have no count. Field types are read from each
class's ``__msgdef__``, the same text the typestore registers.
"""

from __future__ import annotations

import functools
import struct
from collections.abc import Callable
from typing import Any

from usar_replay.core import msgs

__all__ = ["Unsupported", "decoder"]

MAX_SEQUENCE_LENGTH = 2**32 - 1
"""rosbags' default ``Typestore.max_sequence_length`` (the typestore in :mod:`usar_replay.core.cdr`
uses the default): a longer sequence is an error there, so it is one here too."""

# struct code, size (= alignment) of each ROS primitive this module reads; as rosbags reads them
# (``byte`` is a signed char there)
_PRIMITIVES: dict[str, tuple[str, int]] = {
    "bool": ("?", 1),
    "byte": ("b", 1),
    "int8": ("b", 1),
    "uint8": ("B", 1),
    "int16": ("h", 2),
    "uint16": ("H", 2),
    "int32": ("i", 4),
    "uint32": ("I", 4),
    "int64": ("q", 8),
    "uint64": ("Q", 8),
    "float32": ("f", 4),
    "float64": ("d", 8),
}
_BYTE_SEQUENCES = frozenset({"uint8", "int8"})
"""Sequences held as ``bytes`` in :mod:`usar_replay.core.msgs`."""


class Unsupported(Exception):
    """This decoder does not decode these bytes (big-endian, damaged, ...): use rosbags."""


Decoder = Callable[[bytes], msgs.Message]


def decoder(cls: type[msgs.Message]) -> Decoder | None:
    """The generated decoder of ``cls`` (CDR bytes, header included, to a value), or None when
    a field of ``cls`` is of a kind this module does not generate code for."""
    key: Any = cls  # a class is hashable; mypy reads Message's __hash__ as an instance's
    return _decoder(key)


def _fields(cls: type[msgs.Message]) -> list[tuple[str, str, int | None]]:
    """(name, type, array length: None scalar, -1 sequence, N fixed) from ``__msgdef__``;
    message types are named ``pkg/msg/Type``, as :data:`msgs.MESSAGE_TYPES` names them."""
    out: list[tuple[str, str, int | None]] = []
    for line in cls.__msgdef__.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line or "=" in line:  # blank, or a constant
            continue
        typ, name = line.split()
        length: int | None = None
        if typ.endswith("]"):
            typ, _, n = typ[:-1].partition("[")
            length = int(n) if n else -1
        if "/" in typ:
            pkg, _, base = typ.partition("/")
            typ = f"{pkg}/msg/{base}"
        out.append((name, typ, length))
    return out


class _Unknown(Exception):
    """A field this module generates no code for (the caller uses rosbags for the type)."""


class _Gen:
    """Writes one decoding function. ``q`` is the read position in the whole buffer (header
    included, so CDR offset = ``q - 4``); :attr:`mod`/:attr:`rem` say what is known, when the
    code is generated, of the CDR offset there: ``offset % mod == rem``."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.env: dict[str, Any] = {
            "new": object.__new__,
            "Unsupported": Unsupported,
            "MAXSEQ": MAX_SEQUENCE_LENGTH,
        }
        self.n = 0
        self.mod, self.rem = 8, 0
        self.fmt = ""  # fields read since the last flush, as one struct format
        self.names: list[str] = []  # the variables they are read into
        self.skip = 0  # bytes the pending format covers
        self.build: list[str] = []  # constructions waiting for the pending fields

    def var(self, prefix: str) -> str:
        self.n += 1
        return f"{prefix}{self.n}"

    def emit(self, indent: int, line: str) -> None:
        self.lines.append("    " * indent + line)

    def flush(self, indent: int) -> None:
        """Read the pending fixed-layout fields with one ``unpack_from``, then build the values
        that were waiting for them (so a Pose's seven floats are one read, not two)."""
        if self.fmt:
            s = self.var("S")
            self.env[s] = struct.Struct("<" + self.fmt).unpack_from
            self.emit(indent, f"{', '.join(self.names)}, = {s}(b, q)")
            self.emit(indent, f"q += {self.skip}")
            self.fmt, self.names, self.skip = "", [], 0
        for line in self.build:
            self.emit(indent, line)
        self.build = []

    def align(self, indent: int, size: int) -> None:
        """Align the read position to ``size``: statically when the offset is known modulo
        ``size``, else with code (then the offset is known modulo ``size``)."""
        if size == 1:
            return
        if size <= self.mod:
            pad = -self.rem % size
            if pad:
                self.fmt += f"{pad}x"
                self.skip += pad
                self.rem = (self.rem + pad) % self.mod
            return
        self.flush(indent)
        # CDR offset q - 4 rounded up to a multiple of size, back in buffer terms
        self.emit(indent, f"q = ((q + {size - 5}) & -{size}) + 4")
        self.mod, self.rem = size, 0

    def read(self, indent: int, code: str, size: int, count: int = 1) -> list[str]:
        """Queue ``count`` primitives of struct ``code``; returns their variables."""
        self.align(indent, size)
        names = [self.var("v") for _ in range(count)]
        self.fmt += f"{count}{code}" if count > 1 else code
        self.names += names
        self.skip += size * count
        self.rem = (self.rem + size * count) % self.mod
        return names

    def unknown_offset(self) -> None:
        self.mod, self.rem = 1, 0

    def value(self, indent: int, cls: type[msgs.Message]) -> str:
        """Code that decodes one ``cls`` at ``q``; returns the variable that holds it after the
        next :meth:`flush`."""
        fields = _fields(cls)
        kinds = msgs.field_kinds(cls)
        if [f[0] for f in fields] != [k[0] for k in kinds]:
            raise _Unknown(f"{cls.__name__}: definition and fields disagree")
        values: list[str] = []
        for (name, typ, length), (_, kind, elem) in zip(fields, kinds, strict=True):
            values.append(self.field(indent, typ, length, kind, elem, f"{cls.__name__}.{name}"))
        c = self.var("C")
        o = self.var("o")
        self.env[c] = cls
        # the slots are set directly: what the frozen __init__ does, at a third of the cost
        self.build.append(f"{o} = new({c})")
        for (name, _, _), v in zip(fields, values, strict=True):
            setter = self.var("set")
            self.env[setter] = cls.__dict__[name].__set__
            self.build.append(f"{setter}({o}, {v})")
        return o

    def field(
        self, indent: int, typ: str, length: int | None, kind: str, elem: Any, where: str
    ) -> str:
        if length is None:
            if typ == "string":
                return self.string(indent)
            if typ in _PRIMITIVES:
                code, size = _PRIMITIVES[typ]
                (v,) = self.read(indent, code, size)
                return v
            if kind != "msg" or elem.__msgtype__ != typ:
                raise _Unknown(where)
            return self.value(indent, elem)
        if length >= 0:  # a fixed-size array
            if typ not in _PRIMITIVES or kind not in ("floats", "ints") or length == 0:
                raise _Unknown(where)
            code, size = _PRIMITIVES[typ]
            names = self.read(indent, code, size, length)
            return f"({', '.join(names)},)"
        return self.sequence(indent, typ, kind, elem, where)

    def string(self, indent: int) -> str:
        (n,) = self.read(indent, "I", 4)
        self.flush(indent)
        v = self.var("s")
        # rosbags' check_string: a length of at least 1, inside the buffer, NUL-terminated
        self.emit(indent, f"if {n} < 1 or q + {n} > len(b) or b[q + {n} - 1]:")
        self.emit(indent + 1, "raise Unsupported")
        self.emit(indent, f"{v} = b[q:q + {n} - 1].decode()")
        self.emit(indent, f"q += {n}")
        self.unknown_offset()
        return v

    def sequence(self, indent: int, typ: str, kind: str, elem: Any, where: str) -> str:
        (n,) = self.read(indent, "I", 4)
        self.flush(indent)
        v = self.var("a")
        if typ in _PRIMITIVES:
            code, size = _PRIMITIVES[typ]
            if typ in _BYTE_SEQUENCES and kind == "bytes":
                conv = "{b}[q:q + {n}]"
            elif kind in ("floats", "ints") and typ not in _BYTE_SEQUENCES:
                conv = "unpack_from('<%d{c}' % {n}, {b}, q)"
            else:
                raise _Unknown(where)
            self.env["unpack_from"] = struct.unpack_from
            # rosbags' check_sequence (minimum element size) before anything is read
            self.emit(indent, f"if q - 4 + {n} * {size} > len(b) - 4 or {n} > MAXSEQ:")
            self.emit(indent + 1, "raise Unsupported")
            if size > 1:
                self.emit(indent, f"if {n}:")
                self.emit(indent + 1, f"q = ((q + {size - 5}) & -{size}) + 4")
            self.emit(indent, f"{v} = " + conv.format(b="b", n=n, c=code))
            self.emit(indent, f"q += {n} * {size}")
            self.unknown_offset()
            return v
        if kind != "msgs" or elem.__msgtype__ != typ:
            raise _Unknown(where)
        self.emit(indent, f"if q - 4 + {n} > len(b) - 4 or {n} > MAXSEQ:")
        self.emit(indent + 1, "raise Unsupported")
        self.emit(indent, f"{v} = []")
        self.emit(indent, f"for _ in range({n}):")
        self.unknown_offset()  # each element starts wherever the previous one ended
        e = self.value(indent + 1, elem)
        self.flush(indent + 1)
        self.emit(indent + 1, f"{v}.append({e})")
        self.unknown_offset()
        return f"tuple({v})"


@functools.cache
def _decoder(cls: Any) -> Decoder | None:
    gen = _Gen()
    try:
        gen.lines.append("def decode(b):")
        # only little-endian CDR (encapsulation 00 01); rosbags handles the rest and the errors
        gen.emit(1, "if b[:2] != b'\\x00\\x01' or len(b) < 4:")
        gen.emit(2, "raise Unsupported")
        gen.emit(1, "q = 4")
        root = gen.value(1, cls)
        gen.flush(1)
    except _Unknown:
        return None
    # rosbags' size check: at most 3 bytes of padding may follow the message
    gen.emit(1, "if q + 3 < len(b):")
    gen.emit(2, "raise Unsupported")
    gen.emit(1, f"return {root}")
    code = "\n".join(gen.lines) + "\n"
    env = gen.env
    exec(compile(code, f"<cdr decoder of {cls.__msgtype__}>", "exec"), env)
    fn: Decoder = env["decode"]
    return fn
