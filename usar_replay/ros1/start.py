"""How a team's package is started: as its own instructions say, as a TA types it (issue 42).

Why: the course's handout says "only the two commands described in Section 2 will be used":
``roslaunch final_project multiple_robots.launch``, then ``rosrun final_project NODE`` (or a
launch file of the team's), written in the team's ``doc/instructions.txt`` (a required
deliverable) or README; a few teams add a third command (``rosservice call /start "data:
true"``). Every copy of the course template ships nine or more launch files, so no rule of
usar's own ("the only launch file") can start a real class's packages. The start is read, in
this order, the first that names one winning:

1. ``--launch`` / ``--node`` on the command line;
2. the instructor's starts file (``usar batch --starts FILE``, :mod:`.starts_file`): the
   instructor's word, which lives outside the team's folder (issue 50);
3. the team folder's ``usar.toml`` table ``[ros1]`` (``launch``, ``node``, ``after_launch``):
   the team's own word, read as its text is and labelled so (:data:`TEAM_CONFIG`);
4. ``doc/instructions.txt`` (of the team's folder or of the package);
5. the README(s) (of the team's folder, then of the package);
6. the launch file named after the package;
7. the package's only executable (``add_executable``);
8. the package's only launch file.

From a text (4, 5) the package's own ``roslaunch PKG FILE.launch`` and ``rosrun PKG EXE``
commands are the start, read as a person reads prose (:mod:`.start_prose`: in quotes, after a
prompt or a number, with a full stop after them); a command naming another package
(``rosrun rviz rviz``) is not. The ``rosservice call`` / ``rostopic pub`` commands after them
are the TA's third command (:attr:`Start.after_launch`); no other command of a team's, and no
shell text, is ever run. At most one launch file and one executable: a launch file and an
executable both written run together, as the TA's two terminals do. Otherwise
:class:`UnclearStart` names the candidates and how to choose (the instructor's starts file),
which a batch turns into that team's ``no_mission`` verdict.

A written start that cannot start is the TA's fallback, on record (issue 51): a command naming
an executable the package does not build starts its only executable, one naming a launch file
it does not have starts the launch file of that name (another case or extension), and the
start's source says so (``doc/instructions.txt line 5 names `final_project_nod`, which the
package does not build; started its only executable `final_project_node```). With no obvious
fallback the team's verdict is ``no_mission`` with that line, never a crash of code that
never ran.

Where the start came from is kept with it (``doc/instructions.txt line 7``), and the log, ``usar
info``, the grade and the class summary show it. Every file read here is the team's: opened
without following links, regular files only, at most :data:`MAX_TEXT_BYTES`.
"""

from __future__ import annotations

import os
import re
import shlex
import stat
from dataclasses import dataclass
from pathlib import Path

from usar_replay.core import team_parse
from usar_replay.core.errors import TeamFileRefused, UnclearStart
from usar_replay.core.safe_text import safe_line
from usar_replay.ros1.start_prose import Command, clean_name, parse_commands, third_command
from usar_replay.ros1.starts_file import InstructorStart

__all__ = [
    "CONFIG_FILE",
    "TEAM_CONFIG",
    "INSTRUCTIONS",
    "MAX_TEXT_BYTES",
    "Start",
    "UnclearStart",
    "as_built",
    "decide",
    "executables",
    "launch_path",
    "parse_commands",
]

CONFIG_FILE = "usar.toml"
TEAM_CONFIG = f"the team's {CONFIG_FILE} [ros1]"
"""How a start read from a team folder's ``usar.toml`` is labelled: the team's word."""
INSTRUCTIONS = "doc/instructions.txt"
MAX_TEXT_BYTES = 256 * 1024
"""What is read of one instructions file or README (the rest is not looked at)."""
_README = re.compile(r"^readme(\.(md|txt|rst|markdown))?$", re.IGNORECASE)
_ADD_EXECUTABLE = re.compile(r"^[^#\n]*\badd_executable\s*\(\s*([^\s()]+)", re.MULTILINE | re.I)
_INSTALL_PYTHON = re.compile(
    r"^[^#\n]*\bcatkin_install_python\s*\(\s*PROGRAMS\s+([^)]*?)\s+DESTINATION", re.M | re.I
)
_PROJECT = re.compile(r"^[^#\n]*\bproject\s*\(\s*([A-Za-z0-9_]+)", re.MULTILINE | re.I)
_UNKNOWN_BUILD = re.compile(
    r"^[^#\n]*\b(add_executable\s*\(\s*[^\s()]*\$\{(?!PROJECT_NAME\})|add_subdirectory\s*\("
    r"|OUTPUT_NAME\b|RUNTIME_OUTPUT_DIRECTORY\b)",
    re.MULTILINE | re.I,
)
"""What makes the executables a package builds unknowable from its ``CMakeLists.txt`` (a
target usar cannot resolve, a subfolder's, a renamed output): then a written name is checked
after the build instead (:func:`as_built`)."""
_MAX_FILES = 2000
"""Files of a package looked at (its launch files, its scripts); past it, unknown."""
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
        if len(found) > _MAX_FILES:
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
class _Package:
    """What a start is checked against: the package's launch files, the executables its
    ``CMakeLists.txt`` builds, and the names of its files (``rosrun`` runs a script too)."""

    path: Path
    name: str
    launches: list[str]
    exes: list[str]
    files: frozenset[str]
    builds_known: bool
    """Whether :attr:`exes` is all it builds (no ``add_executable`` of a name usar cannot
    resolve, no ``add_subdirectory``): else no written name is called missing."""

    def has_exe(self, exe: str) -> bool:
        return exe in self.exes or exe in self.files or not self.builds_known

    def same_launch(self, name: str) -> str:
        """The package's launch file ``name`` means (its case or extension aside), or ''."""
        stem = name.lower().removesuffix(".xml").removesuffix(".launch")
        found = [f for f in self.launches if f.lower().removesuffix(".launch") == stem]
        return found[0] if len(found) == 1 else ""


def _package(pkg_dir: Path, package: str) -> _Package:
    text = _read_text(pkg_dir / "CMakeLists.txt")
    found = _files(pkg_dir, ("",))
    # a walk cut short (a huge folder) cannot say a file is not there
    unresolved = text is None or bool(_UNKNOWN_BUILD.search(text)) or len(found) > _MAX_FILES
    files = frozenset(p.name for p in found)
    return _Package(
        pkg_dir, package, launch_files(pkg_dir), executables(pkg_dir, package), files,
        not unresolved,
    )  # fmt: skip


def _args(words: tuple[str, ...]) -> list[str]:
    """A roslaunch/rosrun command's names: options and ``name:=value`` left out, each read as
    prose writes it (:func:`.start_prose.clean_name`)."""
    out = [clean_name(w) for w in words[1:] if not w.startswith("-") and ":=" not in w]
    return [w for w in out if w]


def _launch_word(args: list[str]) -> str:
    """The launch file a roslaunch's names mean: the first ``.launch``/``.xml`` one, else the
    second (``roslaunch PKG FILE``)."""
    for arg in args:
        if arg.endswith((".launch", ".xml")):
            return arg
    return args[1] if len(args) >= 2 else ""


def _from_text(text: str, where: str, pkg: _Package) -> Start | None:
    """The start a text writes (None: it writes none of the package's); :class:`UnclearStart`
    when it writes several, or names what the package does not have with no obvious
    fallback (the line that names it, which a batch makes the team's ``no_mission``)."""
    launch: list[tuple[str, int]] = []
    node: list[tuple[str, int]] = []
    after: list[str] = []
    notes: list[tuple[int, str]] = []
    missing: list[tuple[int, str, str]] = []  # (line, name, what the package lacks)
    commands = list(parse_commands(text))
    aliases = _old_names(commands, pkg)
    for cmd in commands:
        w, line = cmd.words, cmd.line
        if w[0] == "roslaunch":
            args = _args(w)
            file = Path(_launch_word(args)).name
            if not file or not ((len(args) >= 2 and args[0] == pkg.name) or file in pkg.launches):
                continue  # another package's (turtlebot3_gazebo's world)
            if file not in pkg.launches:
                other = pkg.same_launch(file)
                if not other:
                    missing.append((line, file, "which the package does not have"))
                    continue
                notes.append((line, f"names `{file}`, which the package does not have; started "
                                    f"its launch file `{other}`"))  # fmt: skip
                file = other
            if file not in [f for f, _ in launch]:
                launch.append((file, line))
        elif w[0] == "rosrun":
            args = _args(w)
            if len(args) < 2 or not (args[0] in (pkg.name, *aliases) or args[1] in pkg.exes):
                continue  # another package's (rosrun rviz rviz)
            exe = args[1]
            if not pkg.has_exe(exe):
                if len(pkg.exes) != 1:
                    missing.append((line, exe, "which the package does not build"))
                    continue
                notes.append((line, f"names `{exe}`, which the package does not build; "
                                    f"started its only executable `{pkg.exes[0]}`"))  # fmt: skip
                exe = pkg.exes[0]
            if exe not in [n for n, _ in node]:
                node.append((exe, line))
        elif launch or node or missing:  # rosservice call / rostopic pub, after the start
            command = shlex.join(w)
            if command not in after:
                after.append(command)
    for line, name, why in missing:
        if name == WORLD_LAUNCH and node:  # usar stands in for the course's world anyway
            notes.append((line, f"names `{name}`, {why}; left out (usar stands in for the "
                                "course's world)"))  # fmt: skip
            continue
        have = _listed(pkg.exes) if "build" in why else _listed(pkg.launches)
        raise UnclearStart(
            f"{where} line {line} names `{safe_line(name)}`, {why} (it has {have}), and no "
            "other start is obvious; the instructor names one with usar batch --starts FILE "
            "(or --node/--launch)"
        )
    if not launch and not node:
        return None
    # the world's launch file beside a launch file of the team's: the team's includes it
    if len(launch) > 1:
        launch = [x for x in launch if x[0] != WORLD_LAUNCH] or launch
    if len(launch) > 1 or len(node) > 1:
        names = [f for f, _ in launch] + [n for n, _ in node]
        raise UnclearStart(
            f"{where} starts {len(names)} things of package {pkg.name} ({', '.join(names)}); "
            "the instructor says which with usar batch --starts FILE (a table per team: "
            'launch = "FILE" or node = "EXE"), or --node/--launch'
        )
    lines = sorted({ln for _, ln in launch + node})
    return Start(
        launch=launch[0][0] if launch else "",
        node=node[0][0] if node else "",
        after_launch=tuple(after),
        source=_where(where, lines, notes),
    )


def _old_names(commands: list[Command], pkg: _Package) -> tuple[str, ...]:
    """The names a text calls this package by when it never writes its own: a package whose
    ``roslaunch`` starts one of this package's launch files (``roslaunch final_project
    multiple_robots.launch`` in a package since renamed ``urban_search_rescue``). The same
    text's ``rosrun`` of that name is then the team's, its executable checked as any other
    (a TA runs the renamed package's node). A launch file this package lacks
    (``turtlebot3_world.launch`` of turtlebot3_gazebo) never makes one, nor does any command
    once the text writes the package's own name."""
    named: dict[str, None] = {}
    for cmd in commands:
        args = _args(cmd.words)
        if not args:
            continue
        if args[0] == pkg.name:
            return ()
        if cmd.words[0] == "roslaunch" and len(args) >= 2:
            file = Path(_launch_word(args)).name
            if file in pkg.launches:
                named[args[0]] = None
    return tuple(named)


def _where(where: str, lines: list[int], notes: list[tuple[int, str]]) -> str:
    """``doc/instructions.txt lines 3, 5``, with what a TA would note of them (``line 5 names
    `final_project_nod`, which the package does not build; started its only executable ...``)."""
    if len(lines) == 1 and len(notes) == 1 and notes[0][0] == lines[0]:
        return f"{where} line {lines[0]} {safe_line(notes[0][1])}"
    at = ", ".join(str(n) for n in lines)
    text = f"{where} line{'s' if len(lines) > 1 else ''} {at}"
    return "; ".join([text, *(f"line {n} {safe_line(note)}" for n, note in notes)])


def _config(folder: Path, pkg: _Package) -> Start | None:
    """The ``[ros1]`` table of the team's ``folder/usar.toml`` (None without one), read as
    the team's text is (issue 50): its launch file and executable checked as a written
    command is, its third commands only ``rosservice call``/``rostopic pub`` ones (any other,
    shell text above all, left out and said so); :class:`UnclearStart` for one that is not
    valid."""
    text = _read_text(folder / CONFIG_FILE)
    if text is None:
        return None
    try:  # bounded as every team file is (core.team_parse: depth, size)
        data = team_parse.toml(text, CONFIG_FILE)
    except TeamFileRefused as err:
        raise UnclearStart(safe_line(str(err))) from None
    table = data.get("ros1")
    if table is None:
        return None
    label = TEAM_CONFIG
    if not isinstance(table, dict):
        raise UnclearStart(f"{label} must be a table")
    launch, node, after = table.get("launch", ""), table.get("node", ""), table.get("after_launch")
    after = [] if after is None else after
    if isinstance(after, str):
        after = [after]
    if not isinstance(launch, str) or not isinstance(node, str):
        raise UnclearStart(f'{label}: launch and node are strings ("go.launch")')
    if not isinstance(after, list) or not all(isinstance(a, str) for a in after):
        raise UnclearStart(f"{label}: after_launch is a list of commands")
    if not (launch or node or after):
        return None
    notes: list[str] = []
    thirds: list[str] = []
    for number, item in enumerate(after, start=1):
        command = third_command(item)
        if command is None:
            notes.append(f"after_launch {number} left out: not a rosservice call or rostopic pub")
        elif command not in thirds:
            thirds.append(command)
    launch = Path(launch).name
    if launch and launch not in pkg.launches:
        other = pkg.same_launch(launch)
        if not other:
            raise UnclearStart(
                f"{label}: launch = {safe_line(launch)!r}: no such launch file in {pkg.name} "
                f"(it has {_listed(pkg.launches)})"
            )
        notes.append(f"launch {launch!r}: the package has {other!r}, started")
        launch = other
    if node and not pkg.has_exe(node):
        if len(pkg.exes) != 1:
            raise UnclearStart(
                f"{label}: node = {safe_line(node)!r}, which the package does not build (it has "
                f"{_listed(pkg.exes)})"
            )
        notes.append(f"node {node!r}, which the package does not build; started its only "
                     f"executable {pkg.exes[0]!r}")  # fmt: skip
        node = pkg.exes[0]
    source = "; ".join([label, *(safe_line(n) for n in notes)])
    return Start(launch, node, tuple(thirds), source)


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
    instructor: InstructorStart | None = None,
) -> Start:
    """The start of ``package`` (at ``pkg_dir``, handed in as ``team_dir``) in the module
    doc's order; :class:`UnclearStart` (a one-line reason naming the candidates) when none
    decides. ``launch``/``node``/``after_launch``: the command line's; ``instructor``: the
    team's table of the instructor's starts file (:mod:`.starts_file`)."""
    launches = launch_files(pkg_dir)
    if launch or node:
        if launch and Path(launch).name not in launches:
            raise UnclearStart(f"--launch {launch}: no such launch file in {package}")
        where = " and ".join(w for w, v in (("--launch", launch), ("--node", node)) if v)
        return Start(Path(launch).name if launch else "", node, after_launch, where)
    pkg = _package(pkg_dir, package)
    if instructor is not None and (instructor.launch or instructor.node):
        if instructor.launch and instructor.launch not in launches:
            raise UnclearStart(
                f"{instructor.label}: launch = {instructor.launch!r}: no such launch file in "
                f"{package} (it has {_listed(launches)})"
            )
        if instructor.node and not pkg.has_exe(instructor.node):
            raise UnclearStart(
                f"{instructor.label}: node = {instructor.node!r}: the package does not build "
                f"it (it has {_listed(pkg.exes)})"
            )
        after = instructor.after_launch or ()
        return Start(instructor.launch, instructor.node, after + after_launch, instructor.source)
    found = _team_start(pkg, team_dir)
    if instructor is not None:  # the instructor's third commands, or only a note
        after = found.after_launch if instructor.after_launch is None else instructor.after_launch
        what = "after_launch from " if instructor.after_launch is not None else "note: "
        found = Start(found.launch, found.node, after, f"{found.source}; {what}{instructor.source}")
    return _with(found, after_launch)


def _team_start(pkg: _Package, team_dir: Path | None) -> Start:
    """The start the team's own files say (its ``usar.toml [ros1]``, its texts), else the
    package's shape."""
    for folder in dict.fromkeys(f for f in (team_dir, pkg.path) if f is not None):
        start = _config(folder, pkg)
        if start is not None:
            if start.launch or start.node:
                return start
            found = _found(pkg, team_dir)  # only after_launch
            return Start(found.launch, found.node, start.after_launch,
                         f"{found.source}; after_launch from {start.source}")  # fmt: skip
    return _found(pkg, team_dir)


def _with(start: Start, after_launch: tuple[str, ...]) -> Start:
    if not after_launch:
        return start
    return Start(start.launch, start.node, start.after_launch + after_launch, start.source)


def _found(pkg: _Package, team_dir: Path | None) -> Start:
    for label, path in _texts(pkg.path, team_dir):
        text = _read_text(path)
        if text is None:
            continue
        start = _from_text(text, safe_line(label), pkg)
        if start is not None:
            return start
    package, exes, launches = pkg.name, pkg.exes, pkg.launches
    if f"{package}.launch" in launches:
        return Start(launch=f"{package}.launch", source="the launch file named after the package")
    if len(exes) == 1:
        return Start(node=exes[0], source="the package's only executable")
    if not exes and len(launches) == 1:
        return Start(launch=launches[0], source="the package's only launch file")
    raise UnclearStart(
        f"package {package}: no roslaunch/rosrun line of it in {INSTRUCTIONS} or a README, and "
        f"{len(exes)} executables ({_listed(exes)}), {len(launches)} launch files; the "
        'instructor names one with usar batch --starts FILE (a table per team: node = "EXE" '
        'or launch = "FILE"), or --node/--launch'
    )


def as_built(node: str, source: str, pkg_dir: Path, devel: Path, package: str) -> Start:
    """The executable to start, checked against what the build made (``devel/lib/PKG/``) and
    the package's files (a script ``rosrun`` finds in its folder, with its x bit): a name it
    did not build, or a script committed without its x bit (``rosrun`` finds it and refuses
    it), is the TA's fallback as in a text (its only built executable, said in the source), or
    :class:`UnclearStart` with that line, never a ``rosrun`` that exits 3 and a team blamed
    for a crash of code that never ran. The command line's and the instructor's names get no
    fallback (a usage error, theirs to fix). A workspace without ``devel/`` is not judged."""
    kept = Start(node=node, source=source)
    lib = devel / "lib" / package
    found = _files(pkg_dir, ("",))
    if not node or not devel.is_dir() or len(found) > _MAX_FILES:
        return kept
    named = [p for p in found if p.name == node]
    if any(_runnable(p) for p in named):
        return kept
    try:
        built = sorted(
            e.name for e in os.scandir(lib) if e.is_file(follow_symlinks=False)
            and os.access(e.path, os.X_OK)
        )  # fmt: skip
    except OSError:
        built = []
    if node in built:
        return kept
    why = "was not built"
    if named:  # rosrun finds it and refuses it: "found ... but not executable"
        why = f"is {safe_line(named[0].relative_to(pkg_dir).as_posix())} with no x bit"
    if len(built) == 1 and not source.startswith(("--", "the instructor's")):
        note = f"`{safe_line(node)}` {why}; started its only executable `{built[0]}`"
        return Start(node=built[0], source=f"{source}; {note}")
    raise UnclearStart(
        f"{source}: `{safe_line(node)}` {why}, so rosrun cannot start it (the package built "
        f"{_listed(built)}); the instructor names one with usar batch --starts FILE (or --node)"
    )


def _runnable(path: Path) -> bool:
    """Whether ``rosrun`` would start the package's file ``path``: a regular file with an x
    bit (as committed: usar keeps a team's modes and never adds one)."""
    try:
        st = path.lstat()
    except OSError:
        return False
    return stat.S_ISREG(st.st_mode) and bool(st.st_mode & 0o111)


def _listed(names: list[str]) -> str:
    if not names:
        return "none"
    return ", ".join(names[:8]) + (f" and {len(names) - 8} more" if len(names) > 8 else "")
