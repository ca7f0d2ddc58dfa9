"""One package's code grade: every metric measured, with its evidence, scored by the rubric.

Why one place: the CLI (``usar code``) and ``usar batch`` grade the same way, and every metric
the JSON promises (docs/code-rubric.md) is filled here, ``None`` where it was not measured and
a note saying why (a tool missing names its Debian package). The package's own code is what the
template does not hold: the template's functions, commented-out lines and PDFs never count
(:mod:`usar_replay.code.template`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from usar_replay.code.budget import DEFAULT, Budget
from usar_replay.code.comments import commented_out
from usar_replay.code.compile import Compiled, compile_check
from usar_replay.code.cppcheck import UNREAD, UNUSED, findings
from usar_replay.code.deliverables import deliverables
from usar_replay.code.docs_own import docs_own
from usar_replay.code.doxygen import Symbol, symbols
from usar_replay.code.report_pdf import Report, report
from usar_replay.code.rubric import Rubric, Scored, score
from usar_replay.code.sources import Submission
from usar_replay.code.style import style
from usar_replay.code.template import NO_TEMPLATE, Template

__all__ = ["Options", "PackageGrade", "grade", "refused"]

_TOOLS = ("doxygen ", "cppcheck ", "clang-format ", "g++ ")
_ON_FILES = re.compile(r"^\S+ (exceeded |failed \(exit)")
"""A tool's note that says the team's files stopped it (a limit, a failure), not that it is
missing or that a header is found nowhere."""
_CODE_METRICS = frozenset(
    {"doc_coverage", "commented_out_lines", "largest_commented_block", "unused_functions",
     "unread_variables", "lint_findings", "classes", "main_lines", "format_changed_share",
     "docs_html", "builds_clean", "compiler_warnings"}
)  # fmt: skip
"""The metrics of the code itself (not the deliverables, not the report)."""


@dataclass(frozen=True, slots=True)
class Options:
    compile: bool = False
    """Run the syntax-only build (~4 s of CPU a file: off by default)."""
    includes: tuple[Path, ...] = ()
    """Extra include folders for it (usar's built messages)."""
    built: Compiled | None = None
    """The package's own build, as ``usar batch`` ran it for the demo
    (:func:`usar_replay.code.compile.from_build`): scored instead of a syntax-only build."""
    budget: Budget = DEFAULT
    """What grading one team may cost (:mod:`usar_replay.code.budget`)."""


@dataclass(frozen=True, slots=True)
class PackageGrade:
    team: str
    package: str
    path: str
    lines: tuple[Scored, ...]
    metrics: dict[str, Any]
    evidence: dict[str, str]
    report: Report | None
    findings: tuple[str, ...] = ()
    verdict: str = "graded"
    """``graded``, or ``unreadable`` (the folder broke a rule; :attr:`findings` says which)."""
    grader: tuple[str, ...] = field(default=())

    @property
    def points(self) -> float:
        return round(sum(s.points for s in self.lines if s.points is not None), 2)

    @property
    def max_points(self) -> float:
        return round(sum(s.line.points for s in self.lines if s.points is not None), 2)


def _own(items: tuple[Symbol, ...], template: Template) -> list[Symbol]:
    """The package's own symbols: not the template's functions (the same qualified name: a
    free ``listen()`` kept from the template is the template's, a method ``Explorer::listen``
    is the team's)."""
    return [s for s in items if not (s.kind == "function" and s.name in template.names)]


def grade(
    sub: Submission,
    rubric: Rubric,
    template: Template = NO_TEMPLATE,
    options: Options | None = None,
) -> PackageGrade:
    """Every metric of ``sub``, scored by ``rubric``."""
    options = options or Options()
    metrics: dict[str, Any] = {}
    evidence: dict[str, str] = {}
    notes: dict[str, str] = {}
    srcs = sub.sources

    syms = symbols(srcs)
    own = _own(syms.items, template)
    if syms.problem:
        for m in ("doc_coverage", "classes", "main_lines", "docs_own"):
            notes[m] = syms.problem
        metrics.update(doc_coverage=None, classes=None, main_lines=None, docs_own=None)
        metrics["docs_html"] = None
        notes["docs_html"] = syms.problem
    else:
        undocumented = [s for s in own if not s.documented]
        metrics["doc_coverage"] = round(1 - len(undocumented) / len(own), 3) if own else None
        said = f"{len(own) - len(undocumented)}/{len(own)} documented" if own else ""
        if undocumented:
            said += f"; first not: {undocumented[0].file}:{undocumented[0].line}"
        evidence["doc_coverage"] = said
        if not own:
            notes["doc_coverage"] = "no classes or functions of its own"
        classes = [s for s in own if s.kind == "class" and s.methods > 0]
        metrics["classes"] = len(classes)
        evidence["classes"] = ", ".join(f"{s.name} ({s.file}:{s.line})" for s in classes[:4])
        mains = [
            s for s in syms.items if s.kind == "function" and s.name == "main" and s.body_lines
        ]
        metrics["main_lines"] = max((s.body_lines for s in mains), default=None)
        if mains:
            longest = max(mains, key=lambda s: s.body_lines)
            evidence["main_lines"] = f"{longest.file}:{longest.line}"
        else:
            notes["main_lines"] = "no main() found"
        own_doc = docs_own(sub, [s.name for s in own])
        metrics["docs_own"] = own_doc.own
        metrics["docs_html"] = own_doc.own is True  # no HTML: the deliverable is missing
        evidence["docs_own"] = evidence["docs_html"] = own_doc.evidence
        if own_doc.own is None:
            notes["docs_own"] = "no Doxygen HTML under doc/"

    d = deliverables(sub)
    metrics["doxyfile"] = bool(d.doxyfile)
    evidence["doxyfile"] = d.doxyfile
    metrics["instructions"] = d.instructions
    evidence["instructions"] = d.instructions_at

    out = commented_out(srcs, template.comment_lines)
    metrics["commented_out_lines"] = out.lines
    metrics["largest_commented_block"] = out.largest
    evidence["commented_out_lines"] = "; ".join(f"{f}:{a} ({n})" for f, a, n in out.blocks[:4])
    evidence["largest_commented_block"] = out.where

    found = findings(srcs, frozenset(n.split("::")[-1] for n in template.names))
    if found.problem:
        for m in ("unused_functions", "unread_variables", "lint_findings"):
            metrics[m] = None
            notes[m] = found.problem
    else:
        for m, items in (
            ("unused_functions", found.of(UNUSED)),
            ("unread_variables", found.of(UNREAD)),
            ("lint_findings", found.lint()),
        ):
            metrics[m] = len(items)
            evidence[m] = "; ".join(f"{f.file}:{f.line} {f.symbol or f.id}" for f in items[:4])

    fmt = style(srcs)
    metrics["format_changed_share"] = fmt.changed_share
    evidence["format_changed_share"] = (
        f"{fmt.changed_lines}/{fmt.lines} lines; most at {fmt.worst}" if fmt.worst else ""
    )
    if fmt.problem:
        notes["format_changed_share"] = fmt.problem

    built = options.built
    not_compiled = False
    if built is None and options.compile:
        built = compile_check(srcs, options.includes)
    if built is not None:
        metrics["compiles"] = built.compiles
        metrics["builds_clean"] = built.clean
        # counted only where it compiles: a package that does not compile is no clean one
        metrics["compiler_warnings"] = built.warnings if built.compiles else None
        evidence["builds_clean"] = evidence["compiler_warnings"] = built.where
        said = built.problem or built.note
        if built.problem:
            notes["compiles"] = built.problem
        if built.compiles is False:  # its line scores 0 (failed below), never "not measured"
            not_compiled = True
            said = "does not compile" + (f"; {said}" if said else "")
        if said:
            notes["builds_clean"] = notes["compiler_warnings"] = said
    else:
        metrics.update(compiles=None, builds_clean=None, compiler_warnings=None)
        notes["builds_clean"] = "not measured: add --compile (a syntax-only build, ~4 s a file)"
        notes["compiler_warnings"] = notes["builds_clean"]

    rep = report(sub, template.pdf_sha256)
    metrics["report_pages"] = rep.pages
    failed = frozenset(
        m for m, note in notes.items() if note.startswith(_TOOLS) and _ON_FILES.search(note)
    ) | ({"compiler_warnings"} if not_compiled else set())
    if not srcs:  # nothing to measure is not clean code: every code line scores 0
        for m in _CODE_METRICS:
            metrics[m] = None
            notes[m] = "no readable C++ sources in the package"
        failed |= _CODE_METRICS
    lines = score(rubric, metrics, evidence, notes, failed)
    return PackageGrade(
        team=sub.name,
        package=sub.package_name,
        path=str(sub.root),
        lines=tuple(lines),
        metrics=dict(sorted(metrics.items())),
        evidence=dict(sorted((k, v) for k, v in evidence.items() if v)),
        report=rep,
        findings=sub.findings,
        grader=rubric.grader,
    )


def refused(team: str, path: str, why: str, rubric: Rubric) -> PackageGrade:
    """The grade of a team whose folder could not be read: every line 0 of its points."""
    lines = tuple(Scored(line, 0.0, None, "", why) for line in rubric.lines)
    return PackageGrade(team, "", path, lines, {}, {}, None, (why,), "unreadable", rubric.grader)
