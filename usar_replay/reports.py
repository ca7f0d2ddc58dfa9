"""Grade reports for people (a table) and machines (JSON, JUnit XML, CSV).

JUnit: one ``<testsuite>`` per recording, one ``<testcase>`` per rubric line (named by its
``Check.id``), so a CI system that grades many student runs shows each failing line by name. A
recording that could not be graded at all (not an MCAP, no scenario attached, a needed topic
missing) is not dropped: it appears as a suite with one ``log.readable`` error case, as a JSON
entry with an ``error``, and as a CSV row with ``passed`` 0 and the error.
"""

from __future__ import annotations

import csv
import io
import json
import xml.etree.ElementTree as ET
from collections.abc import Sequence

from usar_replay.grade import GradeReport

__all__ = ["to_csv", "to_json", "to_junit", "to_table"]

Errors = Sequence[tuple[str, str]]
"""(recording path, one-line reason) of recordings that could not be graded at all."""


def to_table(report: GradeReport) -> str:
    """A fixed-width table: verdict, points, line id and text, measured, threshold, evidence."""
    rows = [("", "points", "id", "rubric line", "measured", "threshold", "evidence")]
    for c in report.checks:
        ev = "" if c.evidence_ns is None else f"t={c.evidence_ns / 1e9:.1f}s"
        rows.append(
            (
                "PASS" if c.passed else "FAIL",
                f"{c.points:g}/{c.max_points:g}",
                c.id,
                c.description,
                c.measured,
                c.threshold,
                ev,
            )
        )
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = [f"Grade of {report.source}"]
    if not report.log_complete:
        lines.append(
            f"WARNING: the log is incomplete ({report.log_problem}); graded as far as it goes"
        )
    for r in rows:
        lines.append("  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip())
    verdict = "PASS" if report.passed else "FAIL"
    if not report.log_complete:
        verdict += " (incomplete log)"
    lines.append(f"Total: {report.points:.4g} / {report.max_points:.4g} points: {verdict}")
    return "\n".join(lines)


def to_json(reports: Sequence[GradeReport], errors: Errors = ()) -> str:
    """A list with one object per recording (see :meth:`GradeReport.to_dict`)."""
    items: list[dict[str, object]] = [r.to_dict() for r in reports]
    items += [
        {"source": src, "passed": False, "error": msg, "log_complete": False, "checks": []}
        for src, msg in errors
    ]
    return json.dumps(items, indent=2, sort_keys=True) + "\n"


def to_junit(reports: Sequence[GradeReport], errors: Errors = ()) -> str:
    """JUnit XML: a suite per recording, a test case per rubric line."""
    suites = ET.Element("testsuites", name="usar grade")
    for r in reports:
        failures = sum(not c.passed for c in r.checks)
        suite = ET.SubElement(
            suites,
            "testsuite",
            name=r.source,
            tests=str(len(r.checks) + (0 if r.log_complete else 1)),
            failures=str(failures),
            errors="0" if r.log_complete else "1",
        )
        if not r.log_complete:
            case = ET.SubElement(suite, "testcase", classname=r.source, name="log.complete")
            ET.SubElement(case, "error", message=r.log_problem)
        for c in r.checks:
            case = ET.SubElement(suite, "testcase", classname=r.source, name=c.id)
            props = ET.SubElement(case, "properties")
            for key, value in (
                ("points", f"{c.points:g}"),
                ("max_points", f"{c.max_points:g}"),
                ("measured", c.measured),
                ("threshold", c.threshold),
                (
                    "evidence_s",
                    "" if c.evidence_ns is None else f"{c.evidence_ns / 1e9:.3f}",
                ),
            ):
                ET.SubElement(props, "property", name=key, value=value)
            if not c.passed:
                ET.SubElement(
                    case, "failure", message=f"{c.description}: {c.measured} (needs {c.threshold})"
                )
    for src, msg in errors:
        suite = ET.SubElement(suites, "testsuite", name=src, tests="1", failures="0", errors="1")
        case = ET.SubElement(suite, "testcase", classname=src, name="log.readable")
        ET.SubElement(case, "error", message=msg)
    ET.indent(suites)
    return ET.tostring(suites, encoding="unicode", xml_declaration=True) + "\n"


def to_csv(reports: Sequence[GradeReport], errors: Errors = ()) -> str:
    """One row per recording: totals, then each rubric line's pass/fail by id."""
    ids: list[str] = []
    for r in reports:
        for c in r.checks:
            if c.id not in ids:
                ids.append(c.id)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["recording", "passed", "points", "max_points", "log_complete", "error", *ids])
    for r in reports:
        by_id = {c.id: c for c in r.checks}
        w.writerow(
            [
                r.source,
                int(r.passed),
                f"{r.points:.4g}",
                f"{r.max_points:.4g}",
                int(r.log_complete),
                r.log_problem,
                *("" if i not in by_id else ("pass" if by_id[i].passed else "fail") for i in ids),
            ]
        )
    for src, msg in errors:
        w.writerow([src, 0, "", "", 0, msg, *("" for _ in ids)])
    return buf.getvalue()
