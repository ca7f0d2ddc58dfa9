"""Grade reports for people (a table that fits the terminal) and machines (JSON, JUnit, CSV).

The machine formats are a contract, documented in ``docs/reports.md`` and versioned by
:data:`SCHEMA_VERSION`: a CI job or a TA's spreadsheet reads them, so a field is never renamed
or re-typed without a new version. A recording that could not be graded at all (not an MCAP,
no scenario attached, a needed topic missing, unreadable) is never dropped: it is an entry of
the same shape with ``status`` ``error``.

A report's strings are partly a team's (the start it read, a frame's name in what was measured)
and partly a log's (anyone's file): each format escapes them with
:mod:`usar_replay.core.safe_text`'s helper for its medium (the table: ``safe_line``, JSON:
``json_data``, CSV: ``csv_row``, JUnit XML: ``safe``, where a raw control is not even XML).
"""

from __future__ import annotations

import dataclasses
import re
import shutil
import textwrap
from collections.abc import Sequence

from usar_replay import __version__
from usar_replay.core.safe_text import csv_row, json_data, safe, safe_line
from usar_replay.core.settings import to_mapping
from usar_replay.grading.verdict import Check, GradeReport

__all__ = [
    "SCHEMA_VERSION",
    "Errors",
    "summary_line",
    "table_width",
    "to_csv",
    "to_json",
    "to_junit",
    "to_table",
]

SCHEMA_VERSION = 1
"""Version of the JSON, JUnit and CSV layouts (``docs/reports.md``)."""
MAX_WIDTH = 100
"""Human output never exceeds this many columns, whatever the terminal."""

Errors = Sequence[tuple[str, str]]
"""(recording path, one-line reason) of recordings that could not be graded at all."""


def table_width() -> int:
    """The terminal's width (``COLUMNS`` first), capped at :data:`MAX_WIDTH`; 100 for a pipe."""
    return max(40, min(MAX_WIDTH, shutil.get_terminal_size((MAX_WIDTH, 24)).columns))


def _evidence(c: Check) -> str:
    return "" if c.evidence_ns is None else f"{c.evidence_ns / 1e9:.1f} s"


_UNIT = re.compile(r"(\d) (s|m|cm|frames)\b")
"""A number and its unit stay on one line when a cell wraps."""


def _wrap(text: str, width: int) -> list[str]:
    """Each paragraph (``\\n``) wrapped on its own; continuation lines indented by two."""
    out: list[str] = []
    for para in _UNIT.sub("\\1\u00a0\\2", text).split("\n"):
        out += textwrap.wrap(para, width, subsequent_indent="  ", break_on_hyphens=False) or [""]
    return [line.replace("\u00a0", " ") for line in out]


def _layout(rows: list[list[str]], width: int, flexible: Sequence[int]) -> list[str]:
    """Columns two spaces apart; the ``flexible`` ones share what the fixed ones leave and wrap
    their text onto more lines, so no line is wider than ``width``."""
    n = len(rows[0])
    natural = [max(len(r[i]) for r in rows) for i in range(n)]
    fixed = sum(natural[i] for i in range(n) if i not in flexible) + 2 * (n - 1)
    room = max(width - fixed, 8 * len(flexible))
    want = sum(natural[i] for i in flexible)
    widths = list(natural)
    if want > room:
        # give each flexible column its share, the smaller ones first (they may need less)
        left, cols = room, sorted(flexible, key=lambda i: natural[i])
        for k, i in enumerate(cols):
            share = left // (len(cols) - k)
            widths[i] = max(min(natural[i], share), 1)
            left -= widths[i]
    out: list[str] = []
    for r in rows:
        cells = [_wrap(v, widths[i]) if i in flexible else [v] for i, v in enumerate(r)]
        for k in range(max(len(c) for c in cells)):
            parts = [(c[k] if k < len(c) else "").ljust(widths[i]) for i, c in enumerate(cells)]
            out.append("  ".join(parts).rstrip())
    return out


def to_table(report: GradeReport, width: int | None = None) -> str:
    """A table for a person: verdict, points, the rubric line, what was measured and what was
    needed, and the sim time of the evidence; the text column wraps to ``width`` (default: the
    terminal's, at most 100 columns), so the table fits an 80-column terminal too."""
    width = width or table_width()
    rows = [["", "points", "rubric line", "measured / needed", "at"]]
    for c in report.checks:
        rows.append(
            [
                "PASS" if c.passed else "FAIL",
                f"{c.points:.3g}/{c.max_points:.3g}",
                safe_line(c.id),
                f"{safe_line(c.measured)}\nneeds {safe_line(c.threshold)}",
                _evidence(c),
            ]
        )
    lines = [f"Grade of {safe_line(report.source)}"]
    if report.started_with:
        lines += textwrap.wrap(safe_line(f"Started with: {report.started_with}"), width)
    if not report.log_complete:
        lines += textwrap.wrap(
            safe_line(
                f"WARNING: the log is incomplete ({report.log_problem}); graded as far as it goes"
            ),
            width,
        )
    lines += _layout(rows, width, flexible=(3,))
    verdict = "PASS" if report.passed else "FAIL"
    if not report.log_complete:
        verdict += " (incomplete log)"
    lines.append(f"Total: {report.points:.4g} / {report.max_points:.4g} points: {verdict}")
    lines.append("'at': the sim time of the evidence (the `usar view` timeline)")
    return "\n".join(safe_line(line) for line in lines)


def summary_line(report: GradeReport | None, source: str, error: str = "") -> str:
    """One line per recording for a batch: verdict, points, path, what failed; it fits the
    terminal (a long path loses its middle, never its file name)."""
    if report is None:
        head, tail = f"ERROR  {'-':>5}  ", f": {error}"
    else:
        verdict = "PASS" if report.passed and report.log_complete else "FAIL"
        head = f"{verdict:<5}  {report.points:>2.4g}/{report.max_points:.4g}  "
        tail = " (incomplete log)" if not report.log_complete else ""
        failed = report.failed_ids()
        if failed:
            tail += f" (failed: {', '.join(failed)})"
    width = table_width()
    source, tail = safe_line(source), safe_line(tail)
    room = max(width - len(head) - len(tail), 24)
    path = source if len(source) <= room else "..." + source[-(room - 3) :]
    text = head + path + tail
    return text if len(text) <= width else text[: width - 3] + "..."


# --- machine output ----------------------------------------------------------------------------


def _number(x: float | None) -> float | None:
    return None if x is None else round(x, 6)


def _check_dict(c: Check) -> dict[str, object]:
    return {
        "id": c.id,
        "description": c.description,
        "passed": c.passed,
        "points": _number(c.points),
        "max_points": _number(c.max_points),
        "measured": {"value": _number(c.value), "unit": c.unit, "text": c.measured},
        "threshold": {
            "value": _number(c.limit),
            "unit": c.unit,
            "op": c.op,
            "text": c.threshold,
        },
        "evidence": None
        if c.evidence_ns is None
        else {"sim_time_s": round(c.evidence_ns / 1e9, 3), "what": c.evidence},
        "rule": c.rule,
    }


def _entry(report: GradeReport | None, source: str, error: str = "") -> dict[str, object]:
    """One recording, graded or not, in one shape (``docs/reports.md``)."""
    if report is None:
        return {
            "source": source,
            "status": "error",
            "error": error,
            "scenario": None,
            "rubric": None,
            "rubric_version": None,
            "started_with": "",
            "passed": False,
            "points": None,
            "max_points": None,
            "log_complete": False,
            "log_problem": "",
            "thresholds": None,
            "checks": [],
        }
    th = report.thresholds
    return {
        "source": report.source,
        "status": "graded",
        "error": "",
        "scenario": report.scenario or None,
        "rubric": report.rubric or None,
        "rubric_version": report.rubric_version or None,
        "started_with": report.started_with,
        "passed": report.passed,
        "points": _number(report.points),
        "max_points": _number(report.max_points),
        "log_complete": report.log_complete,
        "log_problem": report.log_problem,
        "thresholds": None if th is None else _thresholds_dict(th),
        "checks": [_check_dict(c) for c in report.checks],
    }


def _thresholds_dict(th: object) -> dict[str, object]:
    out: dict[str, object] = {}
    for f in dataclasses.fields(th):  # type: ignore[arg-type]
        value = getattr(th, f.name)
        out[f.name] = {"value": value, "unit": f.metadata.get("unit", "")}
    return out


def to_json(reports: Sequence[GradeReport], errors: Errors = ()) -> str:
    """``{"schema_version", "tool", "tool_version", "recordings": [...]}``: graded recordings
    first, in the order given, then those that could not be graded."""
    import json  # deferred: the table alone needs none

    doc = {
        "schema_version": SCHEMA_VERSION,
        "tool": "usar-replay",
        "tool_version": __version__,
        "recordings": [_entry(r, r.source) for r in reports]
        + [_entry(None, src, msg) for src, msg in errors],
    }
    return json.dumps(json_data(doc), indent=2) + "\n"


def _classname(source: str) -> str:
    """A JUnit class name CI tools display as a tree: ``usar.grade.<file stem>``, no path dots."""
    stem = re.sub(r"\.mcap$", "", source.replace("\\", "/").rsplit("/", 1)[-1])
    return "usar.grade." + (re.sub(r"[^A-Za-z0-9_-]+", "_", stem) or "recording")


def to_junit(reports: Sequence[GradeReport], errors: Errors = ()) -> str:
    """JUnit XML: a suite per recording, a test case per rubric line, totals on the root."""
    import xml.etree.ElementTree as ET  # deferred: the table alone needs none

    suites = ET.Element("testsuites", name="usar grade")
    total = {"tests": 0, "failures": 0, "errors": 0}
    seconds = 0.0
    for r in reports:
        failures = sum(not c.passed for c in r.checks)
        n_err = 0 if r.log_complete else 1
        tests = len(r.checks) + n_err
        suite = ET.SubElement(
            suites,
            "testsuite",
            name=r.source,
            tests=str(tests),
            failures=str(failures),
            errors=str(n_err),
            skipped="0",
            time=f"{r.seconds:.3f}",
        )
        props = ET.SubElement(suite, "properties")
        for key, value in (
            ("schema_version", str(SCHEMA_VERSION)),
            ("tool_version", __version__),
            ("scenario", r.scenario),
            ("rubric", r.rubric),
            ("rubric_version", str(r.rubric_version or "")),
            ("points", f"{r.points:.4g}"),
            ("max_points", f"{r.max_points:.4g}"),
            *(
                (f"threshold.{k}", "" if v is None else f"{v:g}")
                for k, v in (to_mapping(r.thresholds) if r.thresholds else {}).items()
            ),
        ):
            ET.SubElement(props, "property", name=key, value=value)
        cls = _classname(r.source)
        if not r.log_complete:
            case = ET.SubElement(suite, "testcase", classname=cls, name="log.complete", time="0")
            ET.SubElement(case, "error", message=r.log_problem)
        for c in r.checks:
            case = ET.SubElement(suite, "testcase", classname=cls, name=c.id, time="0")
            cprops = ET.SubElement(case, "properties")
            for key, value in (
                ("points", f"{c.points:g}"),
                ("max_points", f"{c.max_points:g}"),
                ("measured", c.measured),
                ("measured_value", "" if c.value is None else f"{c.value:g}"),
                ("threshold", c.threshold),
                ("threshold_value", "" if c.limit is None else f"{c.limit:g}"),
                ("unit", c.unit),
                ("evidence_s", "" if c.evidence_ns is None else f"{c.evidence_ns / 1e9:.3f}"),
            ):
                ET.SubElement(cprops, "property", name=key, value=value)
            if not c.passed:
                ET.SubElement(
                    case, "failure", message=f"{c.description}: {c.measured} (needs {c.threshold})"
                )
        total["tests"] += tests
        total["failures"] += failures
        total["errors"] += n_err
        seconds += r.seconds
    for src, msg in errors:
        suite = ET.SubElement(
            suites, "testsuite", name=src, tests="1", failures="0", errors="1", skipped="0",
            time="0.000",
        )  # fmt: skip
        case = ET.SubElement(
            suite, "testcase", classname=_classname(src), name="log.readable", time="0"
        )
        ET.SubElement(case, "error", message=msg)
        total["tests"] += 1
        total["errors"] += 1
    for element in suites.iter():  # a raw control is not XML 1.0: every text shown escaped
        for name, value in element.attrib.items():
            element.set(name, safe(value))
    for key, count in total.items():
        suites.set(key, str(count))
    suites.set("time", f"{seconds:.3f}")
    ET.indent(suites)
    return ET.tostring(suites, encoding="unicode", xml_declaration=True) + "\n"


def to_csv(reports: Sequence[GradeReport], errors: Errors = ()) -> str:
    """One row per recording: totals, then each rubric line's ``pass``/``fail`` by id."""
    import csv  # deferred: the table alone needs none
    import io

    ids: list[str] = []
    for r in reports:
        for c in r.checks:
            if c.id not in ids:
                ids.append(c.id)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(
        csv_row([
            "schema_version",
            "recording",
            "status",
            "passed",
            "points",
            "max_points",
            "log_complete",
            "error",
            *ids,
        ])
    )  # fmt: skip
    for r in reports:
        by_id = {c.id: c for c in r.checks}
        w.writerow(
            csv_row([
                SCHEMA_VERSION,
                r.source,
                "graded",
                int(r.passed),
                f"{r.points:.4g}",
                f"{r.max_points:.4g}",
                int(r.log_complete),
                r.log_problem,
                *("" if i not in by_id else ("pass" if by_id[i].passed else "fail") for i in ids),
            ])
        )  # fmt: skip
    for src, msg in errors:
        w.writerow(csv_row([SCHEMA_VERSION, src, "error", 0, "", "", 0, msg, *("" for _ in ids)]))
    return buf.getvalue()
