"""Red team (issue 50, findings 3, 5, 6): a class whose teams attack usar through their own
files and text, graded by ``usar batch --gradescope --code`` and ``usar code --csv --html``.

- 3: a team folder holding a 5 KB ``usar.toml`` nested 5,000 deep, and one whose launch file
  nests 5,000 elements: each that team's ``no_mission`` with one line; the other teams graded;
  no traceback.
- 5: a ROS 1 team whose README's third command carries ESC sequences (a forged table) and whose
  folder name carries them too: no raw control in any file either command writes (``\\n`` and
  ``\\t`` only where the medium keeps lines), JSON decoded included.
- 6: that folder is named ``=HYPERLINK("https:\\\\evil.invalid","open report")``, and a Python
  team ``-dash``: no CSV cell begins with a formula character; HTML escaped.

Bounded: the fast test runs two Python missions for 1 sim-second (no build); the slow one adds
one ROS 1 package of one Python node (its build only configures).
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest
from class_folder import SPIN, package
from clitools import run_batch
from conftest import one_room

from usar_replay.batch.plan import team_name
from usar_replay.cli.main import main
from usar_replay.core.safe_text import safe
from usar_replay.world.scenario_toml import to_toml

ROOT = Path(__file__).resolve().parents[2]
HONEST = (ROOT / "examples" / "minimal_mission.py").read_text(encoding="utf-8")
ROS1 = Path("/usr/bin/roslaunch").exists()
ESC = "\x1b[2J\x1b[H"
EVIL = '=HYPERLINK("https:\\\\evil.invalid","open report")' + ESC
FORGED = f"{ESC}team   w  total\\nevil  60  60/60"
FORMULA = ("=", "+", "-", "@", "\t", "\r")
HOSTILE = team_name(EVIL)


@pytest.fixture(autouse=True, scope="module")
def _build_cache(module_build_cache: Path) -> None:
    """One build cache for this module: usar's underlay is built once."""


CRASH = (
    f"def main() -> None:\n    print({FORGED!r}, flush=True)\n    raise RuntimeError({FORGED!r})\n"
)


def _bombs(subs: Path) -> None:
    (subs / "toml_bomb").mkdir(parents=True)
    (subs / "toml_bomb" / "mission.py").write_text(HONEST, encoding="utf-8")
    (subs / "toml_bomb" / "usar.toml").write_text(
        "a = " + "[" * 2500 + "]" * 2500 + "\n", encoding="utf-8"
    )
    bomb = package(subs / "launch_bomb", "lb", {"n.py": SPIN.format(name="n")}, {})
    (bomb / "launch" / "go.launch").write_text(
        "<launch>" + "<group>" * 5000 + "</group>" * 5000 + "</launch>\n", encoding="utf-8"
    )


def _hostile_package(folder: Path) -> Path:
    launch = '<launch><node pkg="rt5" type="note.py" name="note" output="screen"/></launch>\n'
    team = package(folder, "rt5", {"note.py": SPIN.format(name="note")}, {"go.launch": launch})
    (team / "README.md").write_text(
        "# rt5\n\n```\nroslaunch rt5 go.launch\n"
        f"rostopic pub -1 /rt5_note std_msgs/String \"data: '{FORGED}'\"\n```\n",
        encoding="utf-8",
    )
    return team


def _files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file() and p.suffix != ".mcap")


def _check_text(path: Path) -> None:
    """No raw control (C0 but newline and tab, C1, DEL, bidi override, line separator) in a
    file; a JSON file's strings decoded checked too; no CSV cell that begins a formula."""
    text = path.read_bytes().decode("utf-8")
    bad = {ch for ch in text if safe(ch) != ch and ch not in "\n\t"}
    assert not bad, f"{path.name}: raw controls {sorted(bad)!r}"
    if path.suffix == ".json":

        def strings(value: object) -> list[str]:
            if isinstance(value, str):
                return [value]
            if isinstance(value, dict):
                return [*value, *(s for v in value.values() for s in strings(v))]
            if isinstance(value, list):
                return [s for v in value for s in strings(v)]
            return []

        for s in strings(json.loads(text)):
            bad = {ch for ch in s if safe(ch) != ch and ch not in "\n\t"}
            assert not bad, f"{path.name}: a string decodes to raw controls {sorted(bad)!r}"
    if path.suffix == ".csv":
        for row in csv.reader(io.StringIO(text)):
            for cell in row:
                assert (
                    not cell.startswith(FORMULA) or cell.lstrip("+-").replace(".", "").isdigit()
                ), f"{path.name}: a cell begins a formula: {cell!r}"
    if path.suffix == ".html":
        assert '("https:' not in text, path.name  # a team's quotes are entities
        assert "<script" not in text.lower()


def _batch(subs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    """``usar batch --gradescope --code`` of ``subs``: its output folder, every file in it
    checked (:func:`_check_text`), the bombs' teams said in one line, no traceback."""
    room = tmp_path / "room.toml"
    room.write_text(to_toml(one_room()), encoding="utf-8")
    out = tmp_path / "out"
    args = ["--max-sim-time", "0.5", "--jobs", "2", "--quiet", "--gradescope", "--code"]
    code, text = run_batch(subs, room, out, *args)
    said = capsys.readouterr()
    assert code == 0, text + said.err
    assert "Traceback" not in text + said.err and "\x1b" not in text + said.err
    rows = {r["team"]: r for r in csv.DictReader(io.StringIO((out / "summary.csv").read_text()))}
    assert rows["toml_bomb"]["problems"] == "usar.toml: nested deeper than 64 levels"
    assert rows["launch_bomb"]["problems"] == (
        "launch/go.launch: elements nested deeper than 64 levels"
    )
    written = _files(out)
    assert {p.name for p in written} >= {
        "summary.csv", "summary.txt", "class.json", "class.html", "results.json",
        "room.grade.json", "code.json", "code.csv", "code.html",
    }  # fmt: skip
    for path in written:
        _check_text(path)
    return out


def test_bombs_and_formulas_in_a_class_of_python_teams(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Python teams (no build): ``-dash`` graded, ``crash`` whose exception is a forged table
    in ESC sequences, the two bombs; then ``usar code`` of packages named as formulas."""
    subs = tmp_path / "subs"
    (subs / "-dash").mkdir(parents=True)
    (subs / "-dash" / "mission.py").write_text(HONEST, encoding="utf-8")
    (subs / "crash.py").write_text(CRASH, encoding="utf-8")
    _bombs(subs)
    out = _batch(subs, tmp_path, capsys)
    rows = {r["team"]: r for r in csv.DictReader(io.StringIO((out / "summary.csv").read_text()))}
    assert set(rows) == {"'-dash", "crash", "toml_bomb", "launch_bomb"}
    assert json.loads((out / "-dash" / "room.grade.json").read_text())["outcome"] == (
        "max_sim_time"
    )
    crash = json.loads((out / "crash" / "results.json").read_text())
    assert "\\x1b[2J" in json.dumps(crash) and "\\u001b" not in json.dumps(crash)

    classes = tmp_path / "code_class"
    for name in (EVIL, "-dash", "+plus"):
        package(classes / name, "p" + str(len(name)), {"n.py": SPIN.format(name="n")}, {})
    code_out = tmp_path / "code"
    code_out.mkdir()
    got = main(["code", str(classes), "--csv", str(code_out / "c.csv"), "--html",
                str(code_out / "c.html"), "--json", str(code_out / "c.json")])  # fmt: skip
    said = capsys.readouterr()
    assert got in (0, 1), said.err
    assert "Traceback" not in said.out + said.err and "\x1b" not in said.out + said.err
    for path in _files(code_out):
        _check_text(path)
    teams = [r["team"] for r in csv.DictReader(io.StringIO((code_out / "c.csv").read_text()))]
    assert sorted(teams) == sorted(["'+plus", "'-dash", "'" + EVIL.replace(ESC, "\\x1b[2J\\x1b[H")])


@pytest.mark.slow
@pytest.mark.skipif(not ROS1, reason="ROS 1 is not installed")
def test_a_ros1_team_whose_start_is_escape_sequences(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The fifth red team's attack: a README's third command carrying ESC sequences (a forged
    table), in a folder named as a formula; its start reaches every file escaped."""
    subs = tmp_path / "subs"
    _hostile_package(subs / EVIL)
    _bombs(subs)
    out = _batch(subs, tmp_path, capsys)
    hostile = json.loads((out / HOSTILE / "room.grade.json").read_text())
    assert hostile["outcome"] == "max_sim_time", hostile.get("outcome_reason")
    table = (out / "summary.txt").read_text()
    assert "\\x1b[2J" in table or "rostopic pub" not in table  # shown, if the start kept it
