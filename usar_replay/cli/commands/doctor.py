"""`usar doctor`: what this machine gives a run, and what that means for grades."""

from __future__ import annotations

import argparse
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


def run(args: argparse.Namespace) -> int:
    from usar_replay.batch.machine import check, isolated

    findings = check()
    width = max(len(f.name) for f in findings)
    for f in findings:
        mark = "ok  " if f.ok else "MISS"
        print(f"{mark} {f.name.ljust(width)}  {f.said}"[:100])
        lead = " " * (width + 7)
        if f.means:
            print(
                textwrap.fill(
                    f.means,
                    100,
                    initial_indent=lead,
                    subsequent_indent=lead,
                    break_on_hyphens=False,
                )
            )
        for line in f.fix:  # a file's lines, flags: as they are, indented under the words
            print(f"{lead}  {line}"[:100])
    whole = isolated(findings)
    print("every run gets its whole isolation here" if whole else "isolation is partial here")
    return 0 if whole else 1
