"""`usar gradescope` as docs/gradescope.md says to use it: its ``run_autograder`` run as written,
in a folder laid out as Gradescope lays it out, ends in a ``results.json`` with the points; an
error in the autograder's setup is one line, and a ``results.json`` that says it."""

from __future__ import annotations

import json
import os
import re
import stat
import subprocess
import sys
from pathlib import Path

from clitools import one_error_line, usar

ROOT = Path(__file__).resolve().parents[3]
DOC = ROOT / "docs" / "gradescope.md"
QUITTER = '''"""Says it is done at its first timer: a whole, short run."""
from usar_replay.api import Node, shutdown


class Quitter(Node):
    def __init__(self) -> None:
        super().__init__("explorer")
        self.create_timer(0.5, lambda: shutdown("done"))


def main() -> list[Node]:
    return [Quitter()]
'''


def _script(name: str) -> str:
    """The ``sh`` block after the doc's line that names ``name``."""
    text = DOC.read_text(encoding="utf-8")
    m = re.search(rf"`{name}`[^\n]*\n\n```sh\n(.*?)```", text, re.S)
    assert m is not None, f"docs/gradescope.md has no {name} block"
    return m.group(1)


def _autograder(tmp_path: Path) -> Path:
    """``autograder/`` as Gradescope lays it out: source (with run_autograder), submission,
    results."""
    root = tmp_path / "autograder"
    for sub in ("source", "submission", "results"):
        (root / sub).mkdir(parents=True)
    run = root / "source" / "run_autograder"
    run.write_text(_script("run_autograder"), encoding="utf-8")
    run.chmod(run.stat().st_mode | stat.S_IXUSR)
    (root / "submission" / "mission.py").write_text(QUITTER, encoding="utf-8")
    return root


def test_the_documented_recipe_grades_a_submission(tmp_path: Path) -> None:
    root = _autograder(tmp_path)
    env = dict(os.environ)
    env["USAR_AUTOGRADER"] = str(root)  # the recipe's /autograder, here
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONPATH"] = str(ROOT)
    env["TMPDIR"] = str(tmp_path)
    done = subprocess.run(
        [str(root / "source" / "run_autograder")],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    results = json.loads((root / "results" / "results.json").read_text(encoding="utf-8"))
    assert results["max_score"] == 60.0 and len(results["tests"]) == 1
    test = results["tests"][0]
    assert test["name"] == "seed0: the course rubric" and "Outcome: done" in test["output"]
    assert results["score"] == test["score"] and results["score"] >= 0
    assert results["output"].startswith("usar batch: ")
    assert {"score", "execution_time", "output", "visibility", "tests"} <= set(results)
    # in place: the submission holds what it held, nothing of the runs
    assert [p.name for p in (root / "submission").iterdir()] == ["mission.py"]


def test_setup_puts_usar_on_the_path_the_recipe_uses() -> None:
    assert "/usr/local/bin/usar" in _script("setup.sh")
    assert _script("run_autograder").strip().splitlines()[-1].startswith("exec usar gradescope")


def test_a_setup_error_is_one_line_and_in_the_results(tmp_path: Path) -> None:
    root = tmp_path / "autograder"
    (root / "submission").mkdir(parents=True)
    results = root / "results" / "results.json"
    out = usar(
        "gradescope", "--submission", str(root / "submission"), "--results", str(results),
        "--run-memory", "-5", cwd=tmp_path,
    )  # fmt: skip
    one_error_line(out, 2, "--run-memory -5")
    said = json.loads(results.read_text(encoding="utf-8"))
    assert said["score"] == 0 and said["output"].startswith("usar: error: --run-memory -5")
    env = {**os.environ, "USAR_AUTOGRADER": str(tmp_path / "nowhere")}
    out = usar("gradescope", cwd=tmp_path, env=env)
    one_error_line(out, 2, "no submission folder here")
    assert (tmp_path / "nowhere" / "results" / "results.json").is_file()
