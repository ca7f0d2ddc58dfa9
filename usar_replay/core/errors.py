"""The one error hierarchy of usar-replay.

Every error a *user* can cause (a bad file, a bad scenario, a bad option) is a :class:`UsarError`;
the CLI prints its message as one line and exits with its ``exit_code``. Anything else is a bug
and is allowed to raise with a traceback.
"""

from __future__ import annotations

from usar_replay.core.safe_text import safe_line

__all__ = [
    "UsarError",
    "UsageError",
    "InvalidScenario",
    "LogError",
    "NotAnMcapFile",
    "IncompleteLog",
    "MissingTopic",
    "MissionEnded",
    "BuildFailed",
    "DetectError",
    "MissingRos1",
    "UnusableSubmission",
    "TeamFileRefused",
    "TreeRefused",
    "ProtocolMismatch",
    "NoPackage",
    "SeveralPackages",
    "UnclearStart",
    "DefinitionRefused",
]


class UsarError(Exception):
    """Base of user-facing errors: ``str(err)`` is one line saying what is wrong and what to do."""

    exit_code: int = 2


class UsageError(UsarError):
    """A command line that cannot be acted on (bad option value, conflicting options)."""

    exit_code = 2


class InvalidScenario(UsarError):
    """A scenario file or value that fails validation; the message names the field."""

    exit_code = 2


class LogError(UsarError):
    """A recording that cannot be read as a usar-replay log."""

    exit_code = 3


class NotAnMcapFile(LogError):
    """The path is missing, empty, or not an MCAP file."""


class IncompleteLog(LogError):
    """The log ends early (truncated or interrupted); what could be read is still usable."""


class MissingTopic(LogError):
    """A topic the job needs is absent from the log."""


class MissionEnded(UsarError):
    """The mission process ended the run: ``verdict`` is ``crashed``, ``hung``,
    ``out_of_memory`` or ``refused``; ``detail`` is the user's traceback or the reason.
    (Raised by :mod:`usar_replay.process.mission_process`, which re-exports it.)"""

    exit_code = 4

    def __init__(self, verdict: str, detail: str) -> None:
        first = detail.strip().splitlines()[-1] if detail.strip() else verdict
        first = safe_line(first)  # the mission's text: printed, never obeyed
        super().__init__(f"the mission {verdict.replace('_', ' ')}: {first}")
        self.verdict = verdict
        self.detail = detail


class BuildFailed(MissionEnded):
    """``build_failed`` from a catkin_make that ran: :attr:`output` as it printed it (paths as
    the build saw them), :attr:`root` the package's folder there, :attr:`flags` the warning
    flags usar added (``usar batch --code`` scores the build's warnings from them). (Raised by
    :mod:`usar_replay.ros1.building.workspace`, which re-exports it.)"""

    def __init__(self, detail: str, output: str, root: str, flags: tuple[str, ...]) -> None:
        super().__init__("build_failed", detail)
        self.output = output
        self.root = root
        self.flags = flags


class DetectError(UsarError):
    """A frame that cannot be decoded (corrupt image bytes in a log). (Raised by
    :mod:`usar_replay.world.detect`, which re-exports it.)"""

    exit_code = 3


class MissingRos1(UsageError):
    """ROS 1 is not installed: the message is the ``apt-get install`` line to run. (Raised by
    :mod:`usar_replay.ros1.building.debian`, which re-exports it.)"""


class UnusableSubmission(UsarError):
    """A team's folder breaks a rule of :mod:`usar_replay.batch.team_files` (a FIFO, a link
    out of it, a file over the caps); ``str()`` says which file and why. The batch makes it
    that team's verdict (``bad_submission``)."""


class TeamFileRefused(UnusableSubmission):
    """A file of a team's that usar will not parse (over its size cap, nested too deep, not
    UTF-8, an ``<!ENTITY>``): ``str()`` names the file and the rule, in one line. (Raised by
    :mod:`usar_replay.core.team_parse`; a batch makes it that team's verdict.)"""


class TreeRefused(UsarError):
    """A built catkin workspace holds something usar will not use (a link leading out, a
    special file); the message says what (one line). (Raised by
    :mod:`usar_replay.ros1.building.tree`:
    the build's verdict is ``build_failed``.)"""

    exit_code = 4


class ProtocolMismatch(MissionEnded):
    """The mission process (or the ROS 1 bridge) answered in another version of the mission
    wire protocol than the recorder's: two installations of usar mixed, or a mission that
    writes to usar's socket itself. Either way the run ends as ``refused`` with this reason (a
    mission can forge any frame, so this is a verdict like any other, never an error outside
    the run). (Raised by :mod:`usar_replay.process.protocol`.)"""

    def __init__(self, detail: str) -> None:
        super().__init__("refused", detail)


class NoPackage(UsageError):
    """No catkin package in the folder given (a batch then looks for a Python mission). (Raised
    by :func:`usar_replay.ros1.building.workspace.find_package`.)"""


class UnclearStart(UsageError):
    """What starts a team's ROS 1 package is not decided by its instructions, its README, its
    ``usar.toml`` or the package's shape: the message names the candidates and how to choose.
    (Raised by :func:`usar_replay.ros1.start.decide`; a batch makes it the team's
    ``no_mission``.)"""


class SeveralPackages(UsageError):
    """Several catkin packages build nodes in the folder given: the message lists them and
    says how to choose one. (Raised by :func:`usar_replay.ros1.building.workspace.find_package`.)"""


class DefinitionRefused(UsarError, ValueError):
    """A ROS 1 message definition past a cap of :class:`usar_replay.core.ros1defs.DefinitionLimits`;
    ``str()`` says which, in one line. A ``ValueError`` too: it is bad input to a parser."""
