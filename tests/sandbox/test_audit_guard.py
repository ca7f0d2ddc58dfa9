"""sandbox/audit_guard: the audit-hook guard installed in a fresh interpreter (it cannot be
removed), which then tries what a mission might: each attempt's outcome is printed and checked
here. Real files in tmp_path; no mocks."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

PROBE = r"""
import json, os, socket, subprocess, sys
from usar_replay.sandbox.audit_guard import GuardPolicy, GuardViolation

mine, work, other = sys.argv[1:4]
policy = GuardPolicy(read_roots=(mine,), write_roots=(work,), deny_roots=(other,))
policy.install()
out = {}

def attempt(name, fn):
    try:
        fn()
        out[name] = "ok"
    except GuardViolation as err:
        out[name] = "refused: " + str(err)
    except OSError as err:
        out[name] = "oserror: " + type(err).__name__

attempt("read_own", lambda: open(os.path.join(mine, "mission.py")).read())
attempt("read_other_team", lambda: open(os.path.join(other, "grade.json")).read())
attempt("list_other_team", lambda: os.listdir(other))
attempt("write_work", lambda: open(os.path.join(work, "scratch.txt"), "w").write("x"))
attempt("write_own", lambda: open(os.path.join(mine, "planted.py"), "w").write("x"))
attempt("remove_other", lambda: os.remove(os.path.join(other, "grade.json")))
attempt("subprocess", lambda: subprocess.run(["true"]))
attempt("socket", lambda: socket.socket())
attempt("proc_self", lambda: open("/proc/self/status").read())
attempt("proc_init", lambda: open("/proc/1/status").read())
attempt("dir_fd", lambda: os.open("grade.json", os.O_RDONLY, dir_fd=os.open(work, os.O_RDONLY)))
attempt("devnull", lambda: open(os.devnull, "w").write("x"))
print(json.dumps(out))
"""


def test_the_guard_allows_a_missions_own_files_and_refuses_the_rest(tmp_path: Path) -> None:
    mine, work, other = tmp_path / "team_a", tmp_path / "run", tmp_path / "team_b"
    for folder in (mine, work, other):
        folder.mkdir()
    (mine / "mission.py").write_text("def main(): pass\n", encoding="utf-8")
    (other / "grade.json").write_text("{}", encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(mine), str(work), str(other)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout)
    allowed = {"read_own", "write_work", "proc_self", "devnull"}
    assert {k for k, v in got.items() if v == "ok"} == allowed, got
    refused = {k: v for k, v in got.items() if k not in allowed}
    assert all(
        v.startswith("refused: usar sandbox: the mission may not ") for v in refused.values()
    )
    assert f"read {other / 'grade.json'}" in refused["read_other_team"]
    assert f"write {mine / 'planted.py'} (only its working directory)" in refused["write_own"]
    assert "start or signal processes" in refused["subprocess"]
    assert "use the network" in refused["socket"]
    assert (work / "scratch.txt").read_text() == "x"
    assert not (mine / "planted.py").exists() and (other / "grade.json").exists()
