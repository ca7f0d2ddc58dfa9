"""An opened run: one recording, read once, with everything every command needs from it.

Why one object: ``usar info``, ``grade``, ``replay`` and ``view`` all need the same facts about a
log (its scenario, its settings, which mission ran, the file's state, the mission's outcome,
what is damaged) and its messages. Each used to open the file and parse the attachments on its
own, with three scenario loaders that disagreed on errors. :func:`open_run` does it once; the
commands take a :class:`Run`.

Two states are kept apart, because they answer different questions:

* :attr:`Run.file_state`: is the *file* whole? ``complete`` (closed, indexed), ``interrupted``
  (closed early, still indexed), ``truncated`` (never closed), ``corrupt``;
* :attr:`Run.outcome`: how did the *mission* end? ``done``, ``time_limit`` (the recorder's
  limit), ``crashed`` / ``hung`` (the mission's code), ``interrupted``, or ``unknown`` for a log
  that does not say.
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

from usar_replay.core import contract
from usar_replay.core.errors import IncompleteLog, LogError, MissingTopic, UsageError
from usar_replay.core.settings import RunSettings
from usar_replay.core.settings import from_toml as settings_from_toml
from usar_replay.log import bag
from usar_replay.world.scenario import Scenario
from usar_replay.world.scenario_toml import from_toml

__all__ = ["MissionInfo", "Run", "open_run"]


@dataclass(frozen=True, slots=True)
class MissionInfo:
    """Which mission code made a log: what ``--mission`` named, its module, its source digest."""

    target: str = "builtin"
    """What ``usar record --mission`` was given (``builtin`` for the built-in mission)."""
    module: str = "usar_replay.missions.usar"
    sha256: str = ""
    """sha256 of the mission's source file(s); empty when the log does not say."""
    usar_version: str = ""

    @classmethod
    def from_toml(cls, text: str) -> MissionInfo:
        data = tomllib.loads(text)
        return cls(
            target=str(data.get("target", "")),
            module=str(data.get("module", "")),
            sha256=str(data.get("sha256", "")),
            usar_version=str(data.get("usar_version", "")),
        )

    def to_toml(self) -> str:
        """TOML through the same library as the settings, so a target path holding a quote or
        a backslash still reads back (f-strings wrote invalid TOML for those)."""
        import tomli_w  # deferred: opening a run never writes TOML

        return tomli_w.dumps(
            {
                "target": self.target,
                "module": self.module,
                "sha256": self.sha256,
                "usar_version": self.usar_version,
            }
        )


@dataclass(slots=True)
class Run:
    """One recording, opened once. Build it with :func:`open_run`."""

    path: Path
    reader: bag.BagReader
    scenario: Scenario | None
    """The world the run used; None when the log has none (or its attachment is unreadable:
    :attr:`problems` says which)."""
    settings: RunSettings
    """The recorded settings (defaults for a log that predates settings.toml: see
    :attr:`settings_recorded`)."""
    settings_recorded: bool
    mission: MissionInfo
    problems: list[str] = field(default_factory=list)
    """What is wrong with the attachments, one line each (the scenario, the settings)."""

    # -- the file ------------------------------------------------------------------------------

    @property
    def file_state(self) -> str:
        """``complete``, ``interrupted``, ``truncated``, ``corrupt`` or ``unknown``."""
        if self.reader.damage is not None and self.reader.has_summary:
            return "corrupt"
        return self.reader.status

    @property
    def damage(self) -> bag.Damage | None:
        """How far a damaged file could be read (None while nothing is known to be damaged)."""
        return self.reader.damage

    @property
    def status_record(self) -> dict[str, str]:
        return self.reader.metadata.get(contract.STATUS_METADATA, {})

    @property
    def outcome(self) -> str:
        """How the mission ended, as the recorder wrote it (``unknown`` when it did not)."""
        return self.status_record.get("outcome", "unknown")

    @property
    def outcome_reason(self) -> str:
        """The recorder's words for the outcome (the user's traceback for ``crashed``)."""
        return self.status_record.get("outcome_reason", "")

    @property
    def run_metadata(self) -> dict[str, str]:
        """Facts about the machine that recorded (versions, renderer)."""
        return self.reader.metadata.get(contract.RUN_METADATA, {})

    @property
    def topics(self) -> dict[str, bag.TopicInfo]:
        return self.reader.topics

    @property
    def start_ns(self) -> int:
        return self.reader.start_ns

    @property
    def end_ns(self) -> int:
        return self.reader.end_ns

    @property
    def duration_s(self) -> float:
        return max(self.end_ns - self.start_ns, 0) / 1e9

    # -- what commands need --------------------------------------------------------------------

    def require_scenario(self) -> Scenario:
        """The scenario, or the error that says why this log cannot be replayed or graded."""
        if self.scenario is not None:
            return self.scenario
        if self.problems:
            raise LogError(f"{self.path}: {self.problems[0]}")
        if self.reader.damage is not None:
            raise IncompleteLog(
                f"{self.path}: {self.reader.damage.describe()}; its "
                f"{contract.SCENARIO_ATTACHMENT} attachment is not in the readable part, so it "
                "cannot be replayed or graded"
            )
        raise MissingTopic(
            f"{self.path}: no {contract.SCENARIO_ATTACHMENT} attached; record it with `usar record`"
        )

    def require_topics(self, topics: Iterable[str]) -> None:
        """Raise :class:`MissingTopic` when a complete log lacks one of ``topics`` (a damaged
        log is let through: the missing part may lie past the damage)."""
        if self.reader.damage is not None:
            return
        missing = [t for t in topics if t not in self.reader.topics]
        if missing:
            raise MissingTopic(
                f"{self.path}: topic {missing[0]} is missing; it cannot be used"
                + (f" (also missing: {', '.join(missing[1:])})" if missing[1:] else "")
            )

    def messages(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
        *,
        decode: bool = True,
    ) -> Iterator[bag.BagMessage]:
        """Messages in log-time order, streaming (as :meth:`bag.BagReader.messages`)."""
        return self.reader.messages(topics, start_ns, end_ns, decode_messages=decode)

    def problem(self) -> str:
        """One line on why the log is not whole (empty when it is)."""
        if self.reader.damage is not None:
            return self.reader.damage.describe()
        if self.file_state != "complete":
            return f"the recording was {self.file_state}"
        return ""


def open_run(path: str | os.PathLike[str], *, check: str = "data") -> Run:
    """Open a recording once: its summary (or a scan of a damaged file) and its attachments.

    ``check``: how much of the file is checked on opening (:data:`bag.CHECKS`). Raises
    :class:`NotAnMcapFile` for something that is not a log and :class:`UsageError` for a path that
    is missing or cannot be read (permissions); a damaged log opens, and says what is damaged.
    """
    p = Path(path)
    reader = bag.BagReader(p, check=check)
    problems: list[str] = []
    attachments = reader.attachments
    scenario: Scenario | None = None
    text = attachments.get(contract.SCENARIO_ATTACHMENT)
    if text is not None:
        try:
            scenario = from_toml(text.decode("utf-8"), source=contract.SCENARIO_ATTACHMENT)
        except UnicodeDecodeError:
            problems.append(f"the attached {contract.SCENARIO_ATTACHMENT} is not text")
        except Exception as err:  # noqa: BLE001 - InvalidScenario and friends: say it, go on
            problems.append(f"the attached scenario is invalid: {err}")
    settings = RunSettings()
    recorded = False
    stext = attachments.get(contract.SETTINGS_ATTACHMENT)
    if stext is not None:
        try:
            settings = settings_from_toml(
                RunSettings, stext.decode("utf-8"), source=contract.SETTINGS_ATTACHMENT
            )
            recorded = True
        except (UnicodeDecodeError, UsageError) as err:
            problems.append(f"the attached {contract.SETTINGS_ATTACHMENT} is invalid: {err}")
    mission = MissionInfo(target="", module="", sha256="")
    mtext = attachments.get(contract.MISSION_ATTACHMENT)
    if mtext is not None:
        try:
            mission = MissionInfo.from_toml(mtext.decode("utf-8"))
        except (UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError):
            problems.append(f"the attached {contract.MISSION_ATTACHMENT} is invalid")
    return Run(
        path=p,
        reader=reader,
        scenario=scenario,
        settings=settings,
        settings_recorded=recorded,
        mission=mission,
        problems=problems,
    )
