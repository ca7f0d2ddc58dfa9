"""Hypothesis strategies for every usar message type, derived from the ROS field types.

The ROS base type of each field (int32, uint8, ...) comes from the typestore's field definitions,
so generated values always fit the wire type: a round-trip failure is then a real bug.
"""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st
from rosbags.typesys.base import Nodetype

from usar_replay.core import msgs
from usar_replay.log import bag

_INT_RANGES = {
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "byte": (-(2**7), 2**7 - 1),  # rosbags packs ROS `byte` as a signed char
    "char": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
}

text = st.text(
    st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), max_size=20
)
floats = st.floats(allow_nan=False, width=64)


def _base(basetype: str) -> st.SearchStrategy[Any]:
    if basetype in _INT_RANGES:
        lo, hi = _INT_RANGES[basetype]
        return st.integers(lo, hi)
    if basetype in ("float64", "float32"):
        return floats if basetype == "float64" else st.floats(allow_nan=False, width=32)
    if basetype == "bool":
        return st.booleans()
    if basetype == "string":
        return text
    raise AssertionError(basetype)


def message(cls: type[msgs.Message]) -> st.SearchStrategy[msgs.Message]:
    """A strategy for any value of ``cls`` that its ROS type can carry."""
    _, fielddefs = bag.typestore().fielddefs[cls.__msgtype__]
    ros = {name: desc for name, desc in fielddefs}
    kwargs: dict[str, st.SearchStrategy[Any]] = {}
    for name, kind, elem in msgs.field_kinds(cls):
        node, detail = ros[name]
        if kind == "msg":
            kwargs[name] = st.deferred(lambda e=elem: message(e))
        elif kind == "msgs":
            kwargs[name] = st.lists(st.deferred(lambda e=elem: message(e)), max_size=3).map(tuple)
        elif kind == "bytes":
            kwargs[name] = st.binary(max_size=64)
        elif kind in ("floats", "ints"):
            (_, (basetype, _)), length = detail
            size = (
                {"min_size": length, "max_size": length}
                if node == Nodetype.ARRAY
                else {"max_size": 8}
            )
            kwargs[name] = st.lists(_base(basetype), **size).map(tuple)
        else:
            kwargs[name] = _base(detail[0])
    return st.builds(cls, **kwargs)
