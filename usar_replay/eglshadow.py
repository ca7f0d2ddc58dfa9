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


def _symbol(path: Path, name: str) -> tuple[int, int] | None:
    """(virtual address, size) of a data symbol in the file's ``.symtab``, or None."""
    from elftools.common.exceptions import ELFError
    from elftools.elf.elffile import ELFFile
    from elftools.elf.sections import SymbolTableSection

    try:
        with path.open("rb") as f:
            elf = ELFFile(f)
            tab = elf.get_section_by_name(".symtab")
            if not isinstance(tab, SymbolTableSection):
                return None
            found = tab.get_symbol_by_name(name) or []
            for sym in found:
                if sym["st_info"]["type"] == "STT_OBJECT" and sym["st_size"] == 1:
                    return int(sym["st_value"]), int(sym["st_size"])
    except (OSError, ELFError):
        return None
    return None


def _load_bias(path: Path) -> int | None:
    """Where the loader placed the file's virtual address 0, from ``/proc/self/maps``."""
    from elftools.common.exceptions import ELFError
    from elftools.elf.elffile import ELFFile

    try:
        real = os.path.realpath(path)
        with path.open("rb") as f:
            loads = [s for s in ELFFile(f).iter_segments() if s["p_type"] == "PT_LOAD"]
        first = min(loads, key=lambda s: s["p_offset"])
        with open("/proc/self/maps", encoding="utf-8") as maps:
            for line in maps:
                fields = line.split(maxsplit=5)
                if len(fields) == 6 and fields[5].strip() == real:
                    start = int(fields[0].split("-")[0], 16)
                    if int(fields[2], 16) == first["p_offset"]:
                        return start - (int(first["p_vaddr"]) - int(first["p_offset"]))
    except (OSError, ELFError, ValueError):
        return None
    return None


def disable_shadow_map(plugin_path: str | os.PathLike[str]) -> bool:
    """Switch the loaded plugin's shadow-map pass off; True when it is off afterwards.

    Call after the plugin is loaded (its file is then mapped into this process) and before
    rendering. Idempotent; every simulator in the process shares the plugin and so the setting.
    """
    path = Path(plugin_path)
    sym = _symbol(path, SHADOW_FLAG)
    bias = _load_bias(path)
    if sym is None or bias is None:
        return False
    flag = ctypes.c_uint8.from_address(bias + sym[0])
    if flag.value not in (0, 1):
        return False
    flag.value = 0
    return True
