"""grading/stored_markers: stored markers read from whichever topic and type a mission used."""

from __future__ import annotations

from usar_replay.core import contract, msgs
from usar_replay.grading.stored_markers import LOOKED, StoredMarkers, is_marker_topic

TRUE = [(0, (2.0, 0.4, 0.2)), (3, (-1.0, 1.0, 0.2))]


def _pose(x: float, y: float) -> msgs.Pose:
    return msgs.Pose(position=msgs.Point(x=x, y=y, z=0.25))


def test_which_topics_may_carry_stored_markers() -> None:
    fta = msgs.FiducialTransformArray.__msgtype__
    assert is_marker_topic(contract.MARKER_POSES, fta)
    assert not is_marker_topic("/fiducial_transforms", fta)  # detections, not stored markers
    assert is_marker_topic("/anything", msgs.PoseArray.__msgtype__)
    assert is_marker_topic("/found_Marker_1", msgs.PoseStamped.__msgtype__)
    assert is_marker_topic("/marker", msgs.Pose.__msgtype__)
    assert not is_marker_topic("/goal", msgs.PoseStamped.__msgtype__)
    assert not is_marker_topic("/marker", msgs.Twist.__msgtype__)


def test_a_fiducial_array_gives_ids_as_published() -> None:
    stored = StoredMarkers(TRUE)
    assert stored.where == LOOKED
    arr = msgs.FiducialTransformArray(
        transforms=(
            msgs.FiducialTransform(
                fiducial_id=7,
                transform=msgs.Transform(translation=msgs.Vector3(x=1.0, y=2.0, z=3.0)),
            ),
        )
    )
    assert stored.note(contract.MARKER_POSES, arr)
    assert stored.by_id == {7: (1.0, 2.0, 3.0)}
    assert stored.where == contract.MARKER_POSES


def test_a_pose_array_is_the_whole_stored_set_by_nearest_true_marker() -> None:
    stored = StoredMarkers(TRUE)
    assert stored.note("/stored", msgs.PoseArray(poses=(_pose(-0.9, 1.1), _pose(1.8, 0.5))))
    assert list(stored.by_id) == [0, 3]
    assert stored.by_id[3] == (-0.9, 1.1, 0.25)
    assert stored.note("/stored", msgs.PoseArray(poses=(_pose(2.1, 0.3),)))
    assert list(stored.by_id) == [0]  # the latest array replaces the set


def test_single_poses_add_up_and_other_topics_are_ignored() -> None:
    stored = StoredMarkers(TRUE)
    assert stored.note("/marker_a", msgs.PoseStamped(pose=_pose(-1.0, 0.9)))
    assert stored.note("/marker_b", _pose(2.0, 0.0))
    assert not stored.note("/goal", msgs.PoseStamped(pose=_pose(0.0, 0.0)))
    assert stored.by_id == {0: (2.0, 0.0, 0.25), 3: (-1.0, 0.9, 0.25)}
    assert stored.where == "/marker_a, /marker_b"


def test_without_true_markers_an_unnamed_pose_has_no_id() -> None:
    stored = StoredMarkers([])
    assert stored.note("/marker", _pose(1.0, 1.0))
    assert stored.by_id == {}
    assert stored.where == "/marker"
