"""The replay's comparison for machines: ``usar replay --json/--junit/--csv``.

Why here and not in the grade reports: these documents embed the grade's formats
(:mod:`usar_replay.grading.reports`) and add the replay's comparison, so they sit above both:
the grading layer never needs to know what a replay is. Same schema version as the grade's.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from usar_replay.core.safe_text import csv_row, json_data, safe
from usar_replay.grading.delta import RubricDelta
from usar_replay.grading.reports import SCHEMA_VERSION, to_json, to_junit
from usar_replay.grading.verdict import GradeReport
from usar_replay.pipeline.replay import ReplayReport

__all__ = ["replay_dict", "replay_to_csv", "replay_to_json", "replay_to_junit"]


def replay_dict(report: ReplayReport) -> dict[str, object]:
    """The replay's comparison as plain data: per topic counts, the first divergence, the
    digest, what changed, and the mission's failure if it had one."""
    d = report.divergence
    return {
        "source": report.source,
        "mission": report.mission,
        "identical": report.identical,
        "regression": report.regression,
        "same_code": report.same_code,
        "settings_changed": report.settings_changed,
        "nondeterministic": report.nondeterministic,
        "ticks": report.ticks,
        "inputs": report.inputs,
        "digest_sha256": report.digest,
        "topics": [
            {
                "topic": t.topic,
                "recorded": t.recorded,
                "replayed": t.replayed,
                "identical": t.identical,
            }
            for _, t in sorted(report.topics.items())
        ],
        "first_divergence": None
        if d is None
        else {
            "topic": d.topic,
            "index": d.index,
            "sim_time_s": d.log_time_ns / 1e9,
            "field": d.field,
            "recorded": d.recorded_value,
            "replayed": d.replayed_value,
        },
        "changes": report.changes.lines(),
        "mission_failure": report.mission_failure,
        "mission_failure_detail": report.mission_failure_detail,
        "log_problem": report.log_problem,
    }


def replay_to_json(
    report: ReplayReport, grades: Sequence[GradeReport] = (), delta: RubricDelta | None = None
) -> str:
    """``usar replay --json``: the grade document's shape (``recordings``: the replayed run's
    grade when ``--grade``, else empty) plus ``replay``, the comparison, with its
    ``rubric_delta`` (null when other code or settings were not graded on both sides)."""
    import json  # deferred: the table alone needs none

    doc = json.loads(to_json(grades))
    doc["replay"] = replay_dict(report)
    doc["replay"]["rubric_delta"] = None if delta is None else delta.as_dict()
    return json.dumps(json_data(doc), indent=2) + "\n"  # the log's and the team's text


def replay_to_junit(report: ReplayReport, grades: Sequence[GradeReport] = ()) -> str:
    """``usar replay --junit``: a suite ``usar.replay`` with a test case per compared topic (a
    failure when it differs) and one for the mission's run, then the grade's suites."""
    import xml.etree.ElementTree as ET  # deferred: the table alone needs none

    root = ET.fromstring(to_junit(grades).split("?>", 1)[-1])
    suite = ET.Element("testsuite", name=f"{report.source} (replay)")
    cls = "usar.replay." + (
        re.sub(r"[^A-Za-z0-9_-]+", "_", re.sub(r"\.mcap$", "", report.source.rsplit("/", 1)[-1]))
        or "recording"
    )
    failures = 0
    case = ET.SubElement(suite, "testcase", classname=cls, name="mission.ran", time="0")
    if report.mission_failure is not None:
        failure = ET.SubElement(case, "failure", message=f"the mission {report.mission_failure}")
        failure.text = safe(report.mission_failure_detail)  # the team's traceback: no raw control
        failures += 1
    for _, t in sorted(report.topics.items()):
        case = ET.SubElement(suite, "testcase", classname=cls, name=t.topic, time="0")
        if not t.all_identical:
            failures += 1
            text = f"recorded {t.recorded}, replayed {t.replayed}, identical {t.identical}"
            d = report.divergence
            if d is not None and d.topic == t.topic:
                text += f"; first divergence at {d.log_time_ns / 1e9:.3f} s: {d.field}"
            ET.SubElement(case, "failure", message=text)
    tests = len(report.topics) + 1
    suite.set("tests", str(tests))
    suite.set("failures", str(failures))
    suite.set("errors", "0")
    suite.set("skipped", "0")
    suite.set("time", "0.000")
    root.insert(0, suite)
    for key, add in (("tests", tests), ("failures", failures)):
        root.set(key, str(int(root.get(key, "0")) + add))
    root.set("name", "usar replay")
    for element in suite.iter():  # a raw control is not XML 1.0: every text shown escaped
        for name, value in element.attrib.items():
            element.set(name, safe(value))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def replay_to_csv(report: ReplayReport) -> str:
    """``usar replay --csv`` without ``--grade``: one row per compared topic."""
    import csv  # deferred: the table alone needs none
    import io

    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["schema_version", "source", "topic", "recorded", "replayed", "identical"])
    for _, t in sorted(report.topics.items()):  # a log's names: csv_row neutralises formulas
        w.writerow(
            csv_row([SCHEMA_VERSION, report.source, t.topic, t.recorded, t.replayed, t.identical])
        )
    return out.getvalue()
