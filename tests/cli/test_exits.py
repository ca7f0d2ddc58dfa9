"""cli/exits: the exit codes are the README's, and an interrupt's is the shell's."""

from __future__ import annotations

import re
import signal
from pathlib import Path

from usar_replay.cli import exits
from usar_replay.core.signals import Terminated, exit_code

README = Path(__file__).resolve().parents[2] / "README.md"


def test_every_code_is_in_the_readmes_table_and_no_other() -> None:
    text = README.read_text(encoding="utf-8").split("## Exit codes", 1)[1].split("\n## ", 1)[0]
    listed = {int(n) for n in re.findall(r"`(\d+)`", text)}
    codes = {getattr(exits, name) for name in exits.__all__}
    assert codes <= listed
    assert listed - codes == {143, 129}  # SIGTERM's and SIGHUP's: exit_code gives them
    assert len(codes) == len(exits.__all__)  # one meaning per number


def test_an_interrupts_code_is_128_plus_its_signal() -> None:
    assert exits.EXIT_INTERRUPTED == exit_code(KeyboardInterrupt()) == 128 + signal.SIGINT
    assert exit_code(Terminated(signal.SIGTERM)) == 143
    assert exit_code(Terminated(signal.SIGHUP)) == 129
