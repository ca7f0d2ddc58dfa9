"""Make pybullet's EGL renderer plugin honour ``shadow=0``.

Why this exists (measured on the 2-core machines this runs on, course world, 640x480):
``getCameraImage(..., shadow=0)`` is ignored by the EGL plugin. Its ``GLInstancingRenderer``
decides by a file-level global, ``bool useShadowMap = true``, and every frame first renders the
whole scene into a 2048x2048 shadow-map depth texture, then shades each pixel against it. On
Mesa's llvmpipe that shadow pass is two thirds of the cost: 105 ms of CPU per frame with it,
34 ms without, and the shadow map also leaves acne stripes on the walls. The plugin has no call
that reaches the flag, so this module finds the flag's address in the plugin's own ELF symbol
table (pyelftools), checks that the byte there holds a C++ ``bool`` and sets it to ``false``
before the first frame is rendered.

It is careful by design: the symbol must be a one-byte data object in a segment the loader
mapped from the very file that is loaded; the byte must read 0 or 1. Anything else (another
build, another platform) changes nothing and answers ``False``, and the simulator then records
that its EGL frames carry the shadow pass, because the two give different pixels.
"""

from __future__ import annotations

import ctypes
import os
from pathlib import Path

__all__ = ["SHADOW_FLAG", "disable_shadow_map"]

SHADOW_FLAG = "useShadowMap"
"""The plugin's global that switches its shadow-map pass on."""


def _flag_and_first_load(path: Path, name: str) -> tuple[int, int, int] | None:
    """From one read of the file: the virtual address of the one-byte data symbol ``name`` in
    its ``.symtab``, and the file offset and virtual address of its first loadable segment
    (what :func:`_load_bias` needs); None when the file has no such symbol."""
    from elftools.common.exceptions import ELFError
    from elftools.elf.elffile import ELFFile
    from elftools.elf.sections import SymbolTableSection

    try:
        with path.open("rb") as f:
            elf = ELFFile(f)
            tab = elf.get_section_by_name(".symtab")
            if not isinstance(tab, SymbolTableSection):
                return None
            flag = next(
                (
                    int(sym["st_value"])
                    for sym in tab.get_symbol_by_name(name) or []
                    if sym["st_info"]["type"] == "STT_OBJECT" and sym["st_size"] == 1
                ),
                None,
            )
            loads = [s for s in elf.iter_segments() if s["p_type"] == "PT_LOAD"]
            if flag is None or not loads:
                return None
            first = min(loads, key=lambda s: s["p_offset"])
            return flag, int(first["p_offset"]), int(first["p_vaddr"])
    except (OSError, ELFError):
        return None


def _load_bias(path: Path, first_offset: int, first_vaddr: int) -> int | None:
    """Where the loader placed the file's virtual address 0, from ``/proc/self/maps``: the
    mapping of this very file at its first loadable segment's offset."""
    try:
        real = os.path.realpath(path)
        with open("/proc/self/maps", encoding="utf-8") as maps:
            for line in maps:
                fields = line.split(maxsplit=5)
                here = len(fields) == 6 and fields[5].strip() == real
                if here and int(fields[2], 16) == first_offset:
                    start = int(fields[0].split("-")[0], 16)
                    return start - (first_vaddr - first_offset)
    except (OSError, ValueError):
        return None
    return None


def disable_shadow_map(plugin_path: str | os.PathLike[str]) -> bool:
    """Switch the loaded plugin's shadow-map pass off; True when it is off afterwards.

    Call after the plugin is loaded (its file is then mapped into this process) and before
    rendering. Idempotent; every simulator in the process shares the plugin and so the setting.
    """
    path = Path(plugin_path)
    facts = _flag_and_first_load(path, SHADOW_FLAG)
    if facts is None:
        return False
    vaddr, first_offset, first_vaddr = facts
    bias = _load_bias(path, first_offset, first_vaddr)
    if bias is None:
        return False
    flag = ctypes.c_uint8.from_address(bias + vaddr)
    if flag.value not in (0, 1):
        return False
    flag.value = 0
    return True
