"""`usar doctor`: what this machine gives a run, and what that means for grades."""

from __future__ import annotations

import argparse
import re
import textwrap

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser(
        "doctor",
        help="say what this machine gives a run (sandbox, cgroups, CPU sets, ROS 1)",
        description=(
            "Check what a run gets here: bubblewrap's sandbox, the container usar runs in "
            "(and the flags it lacks), cgroup v1 or v2 and which controllers usar may write "
            "(on v2, a subtree delegated to usar), CPU sets, real-time priority, size-limited "
            "folders, the kernel's per-user pools, Debian's ROS 1 packages; for each part missing, "
            "what it means for a run's grade. Exit 0 when a run gets all of its isolation, "
            "1 when it is partial."
        ),
    )
    p.set_defaults(func=run)


WIDTH = 100
"""The columns every line keeps within."""


def _wrap(text: str, first: str, rest: str) -> str:
    """``text`` filled to :data:`WIDTH` after ``first``, its continuations after ``rest``.

    Why wrap rather than cut: what runs past the edge is what matters most (bubblewrap's own
    reason at the end of the sandbox line, the last flags of the container's), and a cut line
    lost it."""
    return textwrap.fill(
        text,
        WIDTH,
        initial_indent=first,
        subsequent_indent=rest,
        break_on_hyphens=False,
    )


def _continuation(line: str) -> int:
    """Where a shown-as-is line's continuation starts: under its second column (the cost
    beside a flag, after a gap of two spaces or more), else under its own text."""
    gap = re.search(r"\S( {2,})(?=\S)", line)
    return gap.end() if gap else len(line) - len(line.lstrip())


def run(args: argparse.Namespace) -> int:
    from usar_replay.batch.machine import check, isolated

    findings = check()
    width = max(len(f.name) for f in findings)
    lead = " " * (width + 7)
    for f in findings:
        mark = "ok  " if f.ok else "MISS"
        print(_wrap(f.said, f"{mark} {f.name.ljust(width)}  ", lead))
        if f.means:
            print(_wrap(f.means, lead, lead))
        for line in f.fix:  # a file's lines, flags: as they are, indented under the words
            print(_wrap(line, f"{lead}  ", " " * (len(lead) + 2 + _continuation(line))))
    whole = isolated(findings)
    print("every run gets its whole isolation here" if whole else "isolation is partial here")
    return 0 if whole else 1
