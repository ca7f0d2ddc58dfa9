"""sim/eglshadow: a loaded library's one-byte ``useShadowMap`` global found in its ELF symbol
table and switched off; tried on a small shared library compiled here (as the EGL plugin is
built: a file-level ``bool``), and refused on anything else."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from usar_replay.sim import eglshadow

SOURCE = """
bool useShadowMap = true;
extern "C" int shadow_on(void) { return useShadowMap ? 1 : 0; }
"""


def _plugin(tmp_path: Path, source: str, name: str) -> Path:
    compiler = shutil.which("g++")
    if compiler is None:
        pytest.skip("no C++ compiler here")
    src = tmp_path / f"{name}.cpp"
    src.write_text(source, encoding="utf-8")
    lib = tmp_path / f"{name}.so"
    subprocess.run([compiler, "-shared", "-fPIC", "-O0", "-o", str(lib), str(src)], check=True)
    return lib


def test_the_loaded_flag_is_switched_off(tmp_path: Path) -> None:
    lib = _plugin(tmp_path, SOURCE, "plugin")
    loaded = ctypes.CDLL(str(lib))
    assert loaded.shadow_on() == 1
    assert eglshadow.disable_shadow_map(lib) is True
    assert loaded.shadow_on() == 0
    assert eglshadow.disable_shadow_map(lib) is True  # idempotent


def test_a_file_that_is_not_loaded_or_has_no_flag_changes_nothing(tmp_path: Path) -> None:
    unloaded = _plugin(tmp_path, SOURCE, "unloaded")  # never mapped into this process
    assert eglshadow.disable_shadow_map(unloaded) is False
    wide = _plugin(tmp_path, SOURCE.replace("bool useShadowMap", "int useShadowMap"), "wide")
    ctypes.CDLL(str(wide))
    assert eglshadow.disable_shadow_map(wide) is False  # not a one-byte object


def test_shadow_switch_refuses_a_file_that_is_not_the_loaded_plugin(tmp_path: Path) -> None:
    text = tmp_path / "not-elf.so"
    text.write_text("not an ELF file")
    assert eglshadow.disable_shadow_map(text) is False
    assert eglshadow.disable_shadow_map(tmp_path / "missing.so") is False
    assert eglshadow.disable_shadow_map(sys.executable) is False  # no such symbol there
