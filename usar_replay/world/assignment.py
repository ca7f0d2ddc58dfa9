"""Assignments: what differs between the course's US&R mission, its ROS 2 final project, and any
assignment a course package adds.

Why one value per assignment: recording, replay, grading and viewing are the same machinery for
every assignment (sim -> mission process -> sim, one MCAP, per-tick replay, a streaming rubric);
only names and a few rules differ: which robots there are and what their frames are called,
which robot carries the camera, what the simulator publishes (a mission's inputs) and which tf
links it owns (a mission may not broadcast them), the parameters a mission reads, the built-in
reference mission (a ``module:function`` path). A scenario names its assignment
(``assignment = "ros2-final"``, default ``usar``); :func:`of` gives the :class:`Assignment`, and
record, replay, view and the mission process's loader take everything assignment-specific from
it. The rubric that judges an assignment is not here: the world layer knows nothing of grading;
:mod:`usar_replay.grading.rubrics` maps an assignment's name to its rubric.

One registry (:func:`register`, :func:`by_name`, :func:`of`) holds the assignments: the two
built-in ones, and those a package declares under the entry-point group
``usar_replay.assignments`` (loaded the first time a name is not known; ``docs/assignments.md``).

The worlds and variant makers (:mod:`usar_replay.world.ros2_world`,
:mod:`usar_replay.world.variants`: the planner, numpy and scipy) are imported when first called,
not here: ``usar grade`` reads an assignment only for its rubric and would otherwise spend most
of its start-up loading scipy.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from usar_replay.core import contract
from usar_replay.core.settings import RunSettings
from usar_replay.world.scenario import Scenario, close_matches, course_world, field_error
from usar_replay.world.world_key import WorldKey

if TYPE_CHECKING:
    from usar_replay.world.ros2_world import Ros2Task

__all__ = [
    "ASSIGNMENTS",
    "Assignment",
    "ENTRY_POINT_GROUP",
    "ROS2_FINAL",
    "USAR",
    "by_name",
    "check_known",
    "load_plugins",
    "mission_path",
    "names",
    "of",
    "register",
    "ros2_parameters",
    "usar_parameters",
]

ENTRY_POINT_GROUP = "usar_replay.assignments"
"""Entry points in this group name a function that registers assignments (and their rubrics)."""


class VariantMaker(Protocol):
    """``(world, seed, key=None) -> variant``: a seeded variant, keyed by a secret world key
    when one is given (:mod:`usar_replay.world.world_key`)."""

    def __call__(self, scenario: Scenario, seed: int, key: WorldKey | None = None) -> Scenario: ...


@dataclass(frozen=True, slots=True)
class Assignment:
    """Everything assignment-specific that record, replay, grade and view need."""

    name: str
    """``usar`` or ``ros2-final`` (the scenario's ``assignment``)."""
    title: str
    robots: tuple[contract.RobotFrames, ...]
    """The robots, in the order the simulator publishes them, with their frame names."""
    camera_robot: str
    image_topic: str
    camera_info_topic: str
    sim_base_tf: bool
    """Whether the simulator publishes ``odom -> base_footprint`` on ``/tf``."""
    static_frames: tuple[str, ...]
    """Extra frames the simulator publishes on ``/tf_static`` (the project's ``originN``)."""
    static_links: Callable[[Scenario], tuple[tuple[str, str, float, float, float], ...]]
    """Those links for one world: ``(parent, child, x, y, yaw)``."""
    starts: Callable[[Scenario], tuple[tuple[float, float, float], ...]]
    """Each robot's start pose in ``map``, in :attr:`robots` order."""
    parameters: Callable[[Scenario, RunSettings], dict[str, Any]]
    """The parameters the mission's nodes read (never ground truth)."""
    builtin_mission: str
    """The ``--mission`` name of the reference mission (the default ``--mission``; the log's
    ``mission.toml`` records it): :func:`mission_path` turns it into :attr:`mission`."""
    mission: str
    """The reference mission as a ``module:function`` path (``usar_replay.missions.usar:main``)."""
    world: Callable[[], Scenario]
    """The built-in world."""
    variant: VariantMaker
    """A seeded variant of a world (keyed by the world key when one is given)."""
    course_detections: str = ""
    """The topic of the course's detector, run by the recorder (trusted, a mission input;
    :mod:`usar_replay.pipeline.course_detector`); empty when the world has none."""

    @property
    def robot_names(self) -> tuple[str, ...]:
        return tuple(r.robot for r in self.robots)

    @property
    def sim_topics(self) -> tuple[str, ...]:
        """What the simulator publishes to the mission, in the order it publishes at one tick."""
        return (
            contract.TF_STATIC,
            contract.MAP_TOPIC,
            *((contract.TF,) if self.sim_base_tf else ()),
            self.camera_info_topic,
            self.image_topic,
            *(contract.odom(r) for r in self.robot_names),
        )

    @property
    def sim_frames(self) -> tuple[str, ...]:
        """The tf links (child frames) the simulator owns: a mission may not broadcast them.
        Without the simulator's base link, ``base_footprint`` is the mission's to broadcast."""
        out: list[str] = []
        for f in self.robots:
            out += [f.odom, *((f.base,) if self.sim_base_tf else ()), f.camera, f.optical]
        return (*out, *self.static_frames)

    def frames_of(self, robot: str) -> contract.RobotFrames:
        for f in self.robots:
            if f.robot == robot:
                return f
        raise KeyError(robot)


def usar_parameters(scenario: Scenario, settings: RunSettings) -> dict[str, Any]:
    """The US&R mission's parameters, as the course's launch and parameter files give them:
    ``aruco_lookup_locations.target_k`` ([x, y]), ``<robot>.home`` ([x, y, yaw]) and the run's
    ``mission.*`` and ``detector.*`` settings. Never a marker position."""
    params: dict[str, Any] = {}
    for i, (x, y) in enumerate(scenario.targets):
        params[f"aruco_lookup_locations.target_{i + 1}"] = [float(x), float(y)]
    for start in (scenario.explorer, scenario.follower):
        params[f"{start.name}.home"] = [start.x, start.y, start.yaw]
    _settings_parameters(params, settings)
    return params


def _settings_parameters(params: dict[str, Any], settings: RunSettings) -> None:
    for group in ("mission", "detector"):
        for f in dataclasses.fields(getattr(settings, group)):
            params[f"{group}.{f.name}"] = getattr(getattr(settings, group), f.name)
    params["use_sim_time"] = True


def ros2_parameters(scenario: Scenario, settings: RunSettings) -> dict[str, Any]:
    """The final project's parameters, named as the course's ``final_params.yaml``:
    ``aruco_target.x/y``, ``final_destination.frame_id``, ``final_destination.aruco_K.x/y``,
    plus the run's ``mission.*`` and ``detector.*`` settings. Never the marker's ID or pose."""
    task = task_of(scenario)
    params: dict[str, Any] = {
        "aruco_target.x": task.aruco_target[0],
        "aruco_target.y": task.aruco_target[1],
        "final_destination.frame_id": task.frame_id,
    }
    for k, (x, y) in sorted(task.destinations.items()):
        params[f"final_destination.aruco_{k}.x"] = x
        params[f"final_destination.aruco_{k}.y"] = y
    _settings_parameters(params, settings)
    return params


def _ros2_static(scenario: Scenario) -> tuple[tuple[str, str, float, float, float], ...]:
    origins = task_of(scenario).origins
    return tuple((contract.MAP, o, *origins[o]) for o in contract.ORIGIN_FRAMES)


def task_of(scenario: Scenario) -> Ros2Task:
    """:func:`usar_replay.world.ros2_world.task_of`, imported on first use."""
    from usar_replay.world import ros2_world

    return ros2_world.task_of(scenario)


def _ros2_final_world() -> Scenario:
    from usar_replay.world import ros2_world

    return ros2_world.ros2_final_world()


def _make_ros2_variant(scenario: Scenario, seed: int, key: WorldKey | None = None) -> Scenario:
    from usar_replay.world import ros2_world

    return ros2_world.make_ros2_variant(scenario, seed, key)


def _make_variant(scenario: Scenario, seed: int, key: WorldKey | None = None) -> Scenario:
    from usar_replay.world import variants

    return variants.make_variant(scenario, seed, key)


def _usar_starts(s: Scenario) -> tuple[tuple[float, float, float], ...]:
    return tuple((r.x, r.y, r.yaw) for r in (s.explorer, s.follower))


def _ros2_starts(scenario: Scenario) -> tuple[tuple[float, float, float], ...]:
    return (task_of(scenario).start,)


USAR = Assignment(
    name="usar",
    title="US&R Simplified (explorer and follower)",
    robots=tuple(contract.RobotFrames.usar(r) for r in contract.ROBOTS),
    camera_robot="explorer",
    image_topic=contract.IMAGE,
    camera_info_topic=contract.CAMERA_INFO,
    sim_base_tf=True,
    static_frames=(),
    static_links=lambda scenario: (),
    starts=_usar_starts,
    parameters=usar_parameters,
    builtin_mission="builtin",  # node.mission_target.BUILTIN: the default --mission
    mission="usar_replay.missions.usar:main",
    world=course_world,
    variant=_make_variant,
    course_detections=contract.FIDUCIALS,
)

ROS2_FINAL = Assignment(
    name="ros2-final",
    title="ROS 2 final project (robot1, an ArUco marker names the destination)",
    robots=(contract.ROS2_FRAMES,),
    camera_robot=contract.ROS2_ROBOT,
    image_topic=contract.ROS2_IMAGE,
    camera_info_topic=contract.ROS2_CAMERA_INFO,
    sim_base_tf=False,
    static_frames=contract.ORIGIN_FRAMES,
    static_links=_ros2_static,
    starts=_ros2_starts,
    parameters=ros2_parameters,
    builtin_mission="ros2-final",
    mission="usar_replay.missions.ros2_final:main",
    world=_ros2_final_world,
    variant=_make_ros2_variant,
    course_detections=contract.ARUCO_MARKERS,
)

ASSIGNMENTS: dict[str, Assignment] = {a.name: a for a in (USAR, ROS2_FINAL)}
"""Every known assignment by name (the registry; add to it with :func:`register`)."""

_plugins_loaded = False


def register(assignment: Assignment) -> Assignment:
    """Make ``assignment`` known by its name (its rubric is registered separately, with
    :func:`usar_replay.grading.rubrics.register_rubric`). Registering the same value twice is
    harmless; another assignment under a taken name is a ValueError."""
    known = ASSIGNMENTS.get(assignment.name)
    if known is not None and known != assignment:
        raise ValueError(f"assignment {assignment.name!r} is already registered")
    ASSIGNMENTS[assignment.name] = assignment
    return assignment


def load_plugins() -> None:
    """Call each ``usar_replay.assignments`` entry point's function once (it registers its
    package's assignments and rubrics)."""
    global _plugins_loaded
    if _plugins_loaded:
        return
    _plugins_loaded = True
    for ep in sorted(importlib.metadata.entry_points(group=ENTRY_POINT_GROUP), key=str):
        ep.load()()


def _lookup(name: str) -> Assignment | None:
    if name not in ASSIGNMENTS:
        load_plugins()
    return ASSIGNMENTS.get(name)


def names() -> tuple[str, ...]:
    """The known assignments' names (the built-in ones first)."""
    load_plugins()
    return tuple(ASSIGNMENTS)


def by_name(name: str) -> Assignment:
    """The assignment called ``name`` (KeyError when there is none)."""
    found = _lookup(name)
    if found is None:
        raise KeyError(name)
    return found


def check_known(name: str, source: str = "scenario") -> None:
    """An ``InvalidScenario`` naming the field when no assignment is called ``name``."""
    if _lookup(name) is None:
        known = names()
        close = close_matches(name, known)
        hint = f" (did you mean '{close[0]}'?)" if close else f" (known: {', '.join(known)})"
        raise field_error(source, "assignment", f"unknown assignment {name!r}{hint}")


def of(scenario: Scenario) -> Assignment:
    """The assignment a scenario is for (an ``InvalidScenario`` when it is not known)."""
    check_known(scenario.assignment, f"world {scenario.name}")
    return ASSIGNMENTS[scenario.assignment]


def mission_path(spec: str) -> str | None:
    """The ``module:function`` of a reference mission named by ``--mission`` (``builtin``, or
    an assignment's name or its :attr:`~Assignment.builtin_mission`); None for anything else (a
    file or a module path)."""
    if ":" in spec or "/" in spec or spec.endswith(".py"):
        return None
    for asg in ASSIGNMENTS.values():
        if spec in (asg.name, asg.builtin_mission):
            return asg.mission
    if _plugins_loaded or "." in spec:
        return None
    load_plugins()
    return mission_path(spec)
