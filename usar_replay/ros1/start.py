"""How a team's package is started: as its own instructions say, as a TA types it (issue 42).

Why: the course's handout says "only the two commands described in Section 2 will be used":
``roslaunch final_project multiple_robots.launch``, then ``rosrun final_project NODE`` (or a
launch file of the team's), written in the team's ``doc/instructions.txt`` (a required
deliverable) or README; a few teams add a third command (``rosservice call /start "data:
true"``). Every copy of the course template ships nine or more launch files, so no rule of
usar's own ("the only launch file") can start a real class's packages. The start is read, in
this order, the first that names one winning:

1. ``--launch`` / ``--node`` on the command line;
2. the team folder's ``usar.toml`` table ``[ros1]`` (``launch``, ``node``, ``after_launch``):
   the instructor's word where the team's text is unclear or wrong;
3. ``doc/instructions.txt`` (of the team's folder or of the package);
4. the README(s) (of the team's folder, then of the package);
5. the launch file named after the package;
6. the package's only executable (``add_executable``);
7. the package's only launch file.

From a text (3, 4) the package's own ``roslaunch PKG FILE.launch`` and ``rosrun PKG EXE``
lines are the start (a line naming another package, ``rosrun rviz rviz``, is not), and the
``rosservice call`` / ``rostopic pub`` lines after them are the TA's third command
(:attr:`Start.after_launch`). At most one launch file and one executable: a launch file and an
executable both written run together, as the TA's two terminals do. Otherwise
:class:`UnclearStart` names the candidates and how to choose (``usar.toml``), which a batch
turns into that team's ``no_mission`` verdict.

Where the start came from is kept with it (``doc/instructions.txt line 7``), and the log, ``usar
info``, the grade and the class summary show it. Every file read here is the team's: opened
without following links, regular files only, at most :data:`MAX_TEXT_BYTES`.
"""

from __future__ import annotations

import os
import re
import shlex
import stat
import tomllib
from dataclasses import dataclass
from pathlib import Path

from usar_replay.core.errors import UnclearStart
from usar_replay.core.safe_text import safe_line

__all__ = [
    "CONFIG_FILE",
    "INSTRUCTIONS",
    "MAX_TEXT_BYTES",
    "Start",
    "UnclearStart",
    "decide",
    "executables",
    "launch_path",
    "parse_commands",
]

CONFIG_FILE = "usar.toml"
INSTRUCTIONS = "doc/instructions.txt"
MAX_TEXT_BYTES = 256 * 1024
"""What is read of one instructions file or README (the rest is not looked at)."""
_README = re.compile(r"^readme(\.(md|txt|rst|markdown))?$", re.IGNORECASE)
_COMMAND = re.compile(r"\b(roslaunch|rosrun|rosservice\s+call|rostopic\s+pub)\b")
_ADD_EXECUTABLE = re.compile(r"^[^#\n]*\badd_executable\s*\(\s*([^\s()]+)", re.MULTILINE | re.I)
_INSTALL_PYTHON = re.compile(
    r"^[^#\n]*\bcatkin_install_python\s*\(\s*PROGRAMS\s+([^)]*?)\s+DESTINATION", re.M | re.I
)
_PROJECT = re.compile(r"^[^#\n]*\bproject\s*\(\s*([A-Za-z0-9_]+)", re.MULTILINE | re.I)
_SKIP = frozenset({"build", "devel", "install", ".git", "log", "logs", "__pycache__"})
WORLD_LAUNCH = "multiple_robots.launch"
"""The course's world launch file: written beside a team's node, both are started."""


@dataclass(frozen=True, slots=True)
class Start:
    """What is started, and where that was read."""

    launch: str = ""
    """A launch file of the package (its name), or ''."""
    node: str = ""
    """An executable of the package, or ''."""
    after_launch: tuple[str, ...] = ()
    """Commands run once the graph is up, as a TA types them in a third terminal."""
    source: str = ""
    """Where it was read, for people: ``doc/instructions.txt line 7``, ``usar.toml [ros1]``,
    ``--launch``, ``the only executable``."""

    def commands(self, package: str) -> list[str]:
        """The start as a TA types it, one command each."""
        out = []
        if self.launch:
            out.append(f"roslaunch {package} {self.launch}")
        if self.node:
            out.append(f"rosrun {package} {self.node}")
        return out + list(self.after_launch)


def _read_text(path: Path) -> str | None:
    """A team's text file, or None: never through a link, a regular file only, bounded."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return None
        data = os.read(fd, MAX_TEXT_BYTES)
    except OSError:
        return None
    finally:
        os.close(fd)
    return data.decode("utf-8", errors="replace")


def _files(pkg_dir: Path, names: tuple[str, ...]) -> list[Path]:
    """The package's files with one of ``names`` (``x.launch``), catkin's outputs left out."""
    found: list[Path] = []
    for folder, dirs, files in os.walk(pkg_dir):
        dirs[:] = sorted(d for d in dirs if d not in _SKIP and not d.startswith("."))
        found += [Path(folder) / f for f in sorted(files) if f.endswith(names)]
        if len(found) > 2000:
            break
    return found


def launch_files(pkg_dir: Path) -> list[str]:
    """The package's launch files by name, sorted."""
    return sorted({p.name for p in _files(pkg_dir, (".launch",))})


def launch_path(pkg_dir: Path, name: str) -> str:
    """Where the package's launch file ``name`` lies in it (the first by path, as
    ``roslaunch PKG FILE`` finds it; catkin's outputs, hidden folders and links left out),
    relative to the package; ``name`` itself where it has none."""
    found = sorted(p for p in _files(pkg_dir, (".launch",)) if p.name == Path(name).name)
    return found[0].relative_to(pkg_dir).as_posix() if found else name


def executables(pkg_dir: Path, package: str) -> list[str]:
    """The executables the package's ``CMakeLists.txt`` builds or installs (``add_executable``
    and ``catkin_install_python(PROGRAMS ...)``, outside a comment; ``${PROJECT_NAME}``
    resolved), sorted: what ``rosrun`` finds."""
    text = _read_text(pkg_dir / "CMakeLists.txt") or ""
    project = _PROJECT.search(text)
    name = project.group(1) if project else package
    found = set()
    for match in _ADD_EXECUTABLE.finditer(text):
        exe = match.group(1).replace("${PROJECT_NAME}", name)
        if re.fullmatch(r"[A-Za-z0-9_.+-]+", exe):
            found.add(exe)
    for match in _INSTALL_PYTHON.finditer(text):
        found.update(Path(w).name for w in match.group(1).split() if "$" not in w)
    return sorted(found)


@dataclass(frozen=True, slots=True)
class Command:
    """One command of a text: its words and its line number (1-based)."""

    words: tuple[str, ...]
    line: int


def _pieces(line: str) -> list[str]:
    """The command texts of a line: its code spans when it has any with a command in them
    (``run `rosrun p n` then ...``), else the line; each split at ``&&`` and ``;``."""
    spans = line.split("`")[1::2]
    texts = [s for s in spans if _COMMAND.search(s)] or [line]
    out: list[str] = []
    for text in texts:
        out += [p for p in re.split(r"&&|;|\|\|", text) if p.strip()]
    return out


def _words(text: str) -> tuple[str, ...]:
    """The shell words from the command word on (a prompt, a bullet or prose before it is
    dropped); () when it does not parse."""
    match = _COMMAND.search(text)
    if match is None:
        return ()
    rest = text[match.start() :].strip().rstrip(".,")
    try:
        words = shlex.split(rest, comments=True)
    except ValueError:  # an open quote: the line as plain words
        words = rest.split()
    return tuple(words)


def parse_commands(text: str) -> list[Command]:
    """Every ``roslaunch``, ``rosrun``, ``rosservice call`` and ``rostopic pub`` command of a
    text, in order."""
    out: list[Command] = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not _COMMAND.search(line):
            continue
        for piece in _pieces(line):
            words = _words(piece)
            if words:
                out.append(Command(words, number))
    return out


def _from_text(
    text: str, where: str, package: str, launches: list[str], exes: list[str]
) -> Start | None:
    """The start a text writes (None: it writes none of the package's); :class:`UnclearStart`
    when it writes several."""
    launch: list[tuple[str, int]] = []
    node: list[tuple[str, int]] = []
    after: list[str] = []
    for cmd in parse_commands(text):
        w = cmd.words
        if w[0] == "roslaunch":
            args = [a for a in w[1:] if not a.startswith("-") and ":=" not in a]
            file = Path(args[-1]).name if args else ""
            ours = (len(args) >= 2 and args[0] == package) or file in launches
            known = file.endswith(".launch") and ours and file in launches
            if known and file not in [f for f, _ in launch]:
                launch.append((file, cmd.line))
        elif w[0] == "rosrun":
            args = [a for a in w[1:] if not a.startswith("-") and ":=" not in a]
            ours = len(args) >= 2 and (args[0] == package or args[1] in exes)
            if ours and args[1] not in [n for n, _ in node]:
                node.append((args[1], cmd.line))
        elif launch or node:  # rosservice call / rostopic pub, after the start
            command = shlex.join(w)
            if command not in after:
                after.append(command)
    if not launch and not node:
        return None
    # the world's launch file beside a launch file of the team's: the team's includes it
    if len(launch) > 1:
        launch = [x for x in launch if x[0] != WORLD_LAUNCH] or launch
    if len(launch) > 1 or len(node) > 1:
        names = [f for f, _ in launch] + [n for n, _ in node]
        raise UnclearStart(
            f"{where} starts {len(names)} things of package {package} ({', '.join(names)}); "
            f"say which in the team's {CONFIG_FILE}: [ros1] launch = \"FILE\" or node = \"EXE\""
        )
    lines = sorted({ln for _, ln in launch + node})
    at = ", ".join(str(n) for n in lines)
    return Start(
        launch=launch[0][0] if launch else "",
        node=node[0][0] if node else "",
        after_launch=tuple(after),
        source=f"{where} line{'s' if len(lines) > 1 else ''} {at}",
    )


def _config(folder: Path) -> Start | None:
    """The ``[ros1]`` table of ``folder/usar.toml`` (None without one); :class:`UnclearStart`
    for one that is not valid."""
    text = _read_text(folder / CONFIG_FILE)
    if text is None:
        return None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise UnclearStart(f"{CONFIG_FILE} is not valid TOML: {err}") from None
    table = data.get("ros1")
    if table is None:
        return None
    if not isinstance(table, dict):
        raise UnclearStart(f"{CONFIG_FILE}: [ros1] must be a table")
    launch, node, after = table.get("launch", ""), table.get("node", ""), table.get("after_launch")
    after = [] if after is None else after
    if isinstance(after, str):
        after = [after]
    if not isinstance(launch, str) or not isinstance(node, str):
        raise UnclearStart(f'{CONFIG_FILE}: [ros1] launch and node are strings ("go.launch")')
    if not isinstance(after, list) or not all(isinstance(a, str) for a in after):
        raise UnclearStart(f"{CONFIG_FILE}: [ros1] after_launch is a list of commands")
    if not (launch or node or after):
        return None
    return Start(Path(launch).name, node, tuple(after), f"{CONFIG_FILE} [ros1]")


def _texts(pkg_dir: Path, team_dir: Path | None) -> list[tuple[str, Path]]:
    """(label, path) of the instructions, then the READMEs: the team's folder's, then the
    package's (one file read once)."""
    roots = [r for r in (team_dir, pkg_dir) if r is not None]
    seen: set[Path] = set()
    out: list[tuple[str, Path]] = []

    def add(path: Path) -> None:
        key = path.resolve() if not path.is_symlink() else path
        if key in seen:
            return
        seen.add(key)
        base = team_dir or pkg_dir
        label = path.relative_to(base).as_posix() if path.is_relative_to(base) else path.name
        out.append((label, path))

    for root in roots:
        for name in (INSTRUCTIONS, "instructions.txt", "doc/instructions.md"):
            if (root / name).is_file():
                add(root / name)
    for root in roots:
        try:
            names = sorted(os.listdir(root))
        except OSError:
            continue
        for name in names:
            if _README.match(name) and (root / name).is_file():
                add(root / name)
    return out


def decide(
    pkg_dir: Path,
    package: str,
    *,
    launch: str = "",
    node: str = "",
    team_dir: Path | None = None,
    after_launch: tuple[str, ...] = (),
) -> Start:
    """The start of ``package`` (at ``pkg_dir``, handed in as ``team_dir``) in the module
    doc's order; :class:`UnclearStart` (a one-line reason naming the candidates) when none
    decides. ``launch``/``node``/``after_launch``: the command line's."""
    launches = launch_files(pkg_dir)
    if launch or node:
        if launch and Path(launch).name not in launches:
            raise UnclearStart(f"--launch {launch}: no such launch file in {package}")
        where = " and ".join(w for w, v in (("--launch", launch), ("--node", node)) if v)
        return Start(Path(launch).name if launch else "", node, after_launch, where)
    exes = executables(pkg_dir, package)
    for folder in dict.fromkeys(f for f in (team_dir, pkg_dir) if f is not None):
        start = _config(folder)
        if start is not None:
            if start.launch and start.launch not in launches:
                raise UnclearStart(
                    f"{CONFIG_FILE}: [ros1] launch = {start.launch!r}: no such launch file in "
                    f"{package} (it has {_listed(launches)})"
                )
            if start.launch or start.node:
                return _with(start, after_launch)
            found = _found(pkg_dir, package, team_dir, launches, exes)  # only after_launch
            return Start(found.launch, found.node, start.after_launch + after_launch,
                         f"{found.source}; after_launch from {CONFIG_FILE} [ros1]")
    return _with(_found(pkg_dir, package, team_dir, launches, exes), after_launch)


def _with(start: Start, after_launch: tuple[str, ...]) -> Start:
    if not after_launch:
        return start
    return Start(start.launch, start.node, start.after_launch + after_launch, start.source)


def _found(
    pkg_dir: Path, package: str, team_dir: Path | None, launches: list[str], exes: list[str]
) -> Start:
    for label, path in _texts(pkg_dir, team_dir):
        text = _read_text(path)
        if text is None:
            continue
        start = _from_text(text, safe_line(label), package, launches, exes)
        if start is not None:
            return start
    if f"{package}.launch" in launches:
        return Start(launch=f"{package}.launch", source="the launch file named after the package")
    if len(exes) == 1:
        return Start(node=exes[0], source="the package's only executable")
    if not exes and len(launches) == 1:
        return Start(launch=launches[0], source="the package's only launch file")
    raise UnclearStart(
        f"package {package}: no roslaunch/rosrun line of it in {INSTRUCTIONS} or a README, and "
        f"{len(exes)} executables ({_listed(exes)}), {len(launches)} launch files; name one in "
        f"the team's {CONFIG_FILE}: [ros1] node = \"EXE\" or launch = \"FILE\" (or --node/--launch)"
    )


def _listed(names: list[str]) -> str:
    if not names:
        return "none"
    return ", ".join(names[:8]) + (f" and {len(names) - 8} more" if len(names) > 8 else "")
