"""Test helpers that run a shell script in a throwaway Debian 12 VM (``../shared/vm/run.sh``:
systemd as PID 1, the unified cgroup v2 hierarchy, root over ssh) with a copy of this checkout,
and read back what each step of the script did.

Why a VM: the machines the suite usually runs on have cgroup v1 and no systemd, and a fresh
Debian 12 install has neither (issue 49). The VM is the stock one, so what passes there passes
on an instructor's machine. Under TCG emulation it is slow (boot 30-90 s, Python 5-20x slower),
so the scripts stay short and every step says its exit status and seconds on one marker line.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VM_DIR = Path(os.environ.get("USAR_VM_DIR", "/var/tmp/usar-vm"))
WHEELHOUSE = VM_DIR / "wheelhouse-usar"
VENV_IMAGE = "debian12-usar-venv"
BASE_IMAGE = "debian12"

_OUT = "" if str(VM_DIR) == "/var/tmp/usar-vm" else f" {VM_DIR}"  # make-image.sh's OUT_DIR
_BUILD = {
    "wheelhouse": f"../shared/vm/make-wheelhouse.sh . {WHEELHOUSE}",
    BASE_IMAGE: f"../shared/vm/make-image.sh{_OUT}",
    VENV_IMAGE: (
        f"../shared/vm/make-image.sh --name {VENV_IMAGE} --extra-apt-from-readme README.md "
        f"--venv-wheelhouse {WHEELHOUSE}{_OUT}"
    ),
}

PRELUDE = r"""
step() {  # step NAME 'ALLOWED EXIT CODES' <<< COMMAND: one marker line per step; stop on a bad code
    local name=$1 allowed=$2 cmd t0 rc
    cmd=$(cat)
    echo "@@start $name"
    t0=$SECONDS
    bash -c "$cmd" </dev/null 2>&1
    rc=$?
    echo "@@step $name rc=$rc s=$((SECONDS - t0))"
    [[ " $allowed " == *" $rc "* ]] || { echo "@@abort $name"; exit 90; }
}
"""


def tools() -> Path | None:
    """The folder of ``run.sh`` (``USAR_VM_TOOLS``, else ``../shared/vm`` beside the checkout
    or beside the folder that holds it, as in a worktree)."""
    given = os.environ.get("USAR_VM_TOOLS")
    near = [ROOT.parent / "shared/vm", ROOT.parents[1] / "shared/vm"]
    for folder in [Path(given)] if given else near:
        if (folder / "run.sh").is_file():
            return folder
    return None


def missing(image: str, wheelhouse: bool = False) -> str:
    """'' when a VM of ``image`` can start here; else one line: what is missing and the command
    (from the checkout's root) that builds it."""
    if tools() is None:
        return "no ../shared/vm/run.sh beside this checkout (set USAR_VM_TOOLS to its folder)"
    if shutil.which("qemu-system-x86_64") is None or shutil.which("qemu-img") is None:
        return f"no qemu here: `{_BUILD[BASE_IMAGE]}` installs it and builds the base image"
    ready = VM_DIR / (".image-ready" if image == BASE_IMAGE else f"{image}.ready")
    if not ready.is_file():
        return f"no VM image {VM_DIR / image}.qcow2: build it with `{_BUILD[image]}`"
    if wheelhouse and not (WHEELHOUSE / "simple").is_dir():
        return f"no wheelhouse {WHEELHOUSE}: build it with `{_BUILD['wheelhouse']}`"
    return ""


def copy_checkout(dest: Path) -> Path:
    """This checkout as a clone with its local edits would hold it: tracked files and untracked
    ones git does not ignore (no .git, no .venv, no caches, no recordings)."""
    listed = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT, capture_output=True, check=True,
    ).stdout.decode().split("\0")  # fmt: skip
    for rel in filter(None, listed):
        src = ROOT / rel
        if src.is_file():  # a tracked file deleted in the work tree is left out
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / rel)
    return dest


@dataclass(frozen=True)
class Step:
    """One step of a VM script: its exit status, its seconds (in the VM) and what it printed."""

    rc: int
    seconds: int
    output: str


@dataclass(frozen=True)
class VmRun:
    """A finished ``run.sh``: its exit status, the seconds it took here (boot and copy
    included), its whole output (also in ``log``) and the steps the script reached."""

    rc: int
    seconds: float
    output: str
    log: Path
    steps: dict[str, Step]

    def tail(self, chars: int = 4000) -> str:
        """The end of the output, for an assertion message (the whole of it is in ``log``)."""
        return f"(whole output: {self.log})\n" + self.output[-chars:]

    def timings(self) -> str:
        """One line: the whole run's seconds and each step's."""
        each = ", ".join(f"{name} {s.seconds} s (rc {s.rc})" for name, s in self.steps.items())
        return f"VM run {self.seconds:.0f} s in all: {each}"


def steps_of(output: str) -> dict[str, Step]:
    """The ``@@start NAME`` ... ``@@step NAME rc=N s=T`` sections of a script's output."""
    found: dict[str, Step] = {}
    lines: list[str] = []
    for line in output.splitlines():
        if line.startswith("@@start "):
            lines = []
            continue
        # a step whose output has no final newline leaves its last line before the marker
        done = re.fullmatch(r"(.*?)@@step (\S+) rc=(\d+) s=(\d+)", line.rstrip())
        if done:
            lines += [done[1]] if done[1] else []
            found[done[2]] = Step(int(done[3]), int(done[4]), "\n".join(lines))
        else:
            lines.append(line)
    return found


def step(name: str, command: str, allowed: tuple[int, ...] = (0,)) -> str:
    """The script text of one step: ``command`` run by bash, stopping the script when its exit
    status is not one of ``allowed``."""
    codes = " ".join(str(c) for c in allowed)
    head = f"step {shlex.quote(name)} {shlex.quote(codes)} <<'USAR_VM_STEP'"
    return f"{head}\n{command}\nUSAR_VM_STEP\n"


def run_in_vm(
    folder: Path,
    script: str,
    image: str,
    timeout_s: int,
    wheelhouse: Path | None = None,
    mem_mib: int = 4096,
) -> VmRun:
    """Boot ``image``, copy ``folder`` in at its own path, run ``script`` (bash, as root, in
    ``folder``) and power off. ``wheelhouse`` is shared read-only at /wheels and given to pip."""
    run_sh = tools()
    assert run_sh is not None, missing(image)
    (folder / "check.sh").write_text(f"set -u\ncd {shlex.quote(str(folder))}\n{PRELUDE}\n{script}")
    log = folder.parent / f"{folder.name}.vm.log"
    argv = [
        "nice", "-n", "10", str(run_sh / "run.sh"), "--image", image, "--share", str(folder),
        "--vm-dir", str(VM_DIR),
        "--mem", str(mem_mib), "--cpus", "2",
        *(["--wheelhouse", str(wheelhouse)] if wheelhouse else []),
        "--", "bash", str(folder / "check.sh"),
    ]  # fmt: skip
    # boot: 30-90 s on a quiet host, 300-420 s when its CPUs are busy (run.sh's TCG default 420)
    env = {"VM_BOOT_TIMEOUT": "900", **os.environ, "VM_CMD_TIMEOUT": str(timeout_s)}
    start = time.monotonic()
    with log.open("w") as out:
        proc = subprocess.run(
            argv, stdout=out, stderr=subprocess.STDOUT, env=env, timeout=timeout_s + 900,
            check=False,
        )  # fmt: skip
    seconds = time.monotonic() - start
    text = log.read_text(errors="replace")
    return VmRun(proc.returncode, seconds, text, log, steps_of(text))


def pytest_counts(output: str) -> dict[str, int]:
    """The counts of pytest's last summary line (``3 passed, 1 skipped in 9.1s``)."""
    for line in reversed(output.splitlines()):
        if re.search(r"\bin [\d.]+s\b", line):
            counts = {k: int(n) for n, k in re.findall(r"(\d+) ([a-z]+)", line)}
            return {k: n for k, n in counts.items() if not k.startswith("warning")}
    return {}


def doctor_all_ok(output: str) -> bool:
    """Whether ``usar doctor`` said ``ok`` on every check and that a run gets all its isolation
    (its lines that do not start with a space: one per check, then the verdict)."""
    lines = [line for line in output.splitlines() if line and not line.startswith(" ")]
    checks, verdict = lines[:-1], lines[-1:] if lines else []
    return (
        bool(checks)
        and all(c.startswith("ok ") for c in checks)
        and verdict == ["every run gets its whole isolation here"]
    )


def readme_test_command(readme: Path = ROOT / "README.md") -> tuple[str, str]:
    """The README's "Install and run the tests" command as written, cut in two: its apt part
    (``apt-get update && apt-get install ...``) and its install part (the venv and ``pip
    install '.[test]'``), without the ``python -m pytest`` that ends it (the whole suite is
    too slow under emulation). The same line ``make-image.sh --extra-apt-from-readme`` reads."""
    lines = readme.read_text(encoding="utf-8").splitlines()
    after = next(i for i, line in enumerate(lines) if "Install and run the tests" in line)
    line = next(x for x in lines[after:] if "apt-get" in x and " install " in x)
    parts = [p.strip() for p in line.split("&&")]
    last_apt = max(i for i, p in enumerate(parts) if p.startswith("apt-get"))
    rest = parts[last_apt + 1 :]
    assert rest and rest[-1] == "python -m pytest", f"README's test command changed: {line}"
    return " && ".join(parts[: last_apt + 1]), " && ".join(rest[:-1])
