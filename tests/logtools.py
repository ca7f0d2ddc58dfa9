"""Test helpers that build and edit logs: digests, edited copies, synthetic runs."""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path

from usar_replay import bag, msgs
from usar_replay.info import SCENARIO_ATTACHMENT
from usar_replay.scenario import Scenario, to_toml


def digest(path: Path) -> str:
    """sha256 over every message's topic, log time and CDR bytes, in log order."""
    h = hashlib.sha256()
    for m in bag.BagReader(path).messages(decode_messages=False):
        h.update(m.topic.encode() + m.log_time_ns.to_bytes(8, "little") + m.data)
    return h.hexdigest()


Edit = Callable[[bag.BagMessage], msgs.Message | bool | None]


def rewrite(src: Path, dst: Path, edit: Edit) -> None:
    """Copy a log; ``edit`` returns a replacement message, False to drop it, None to keep it."""
    reader = bag.BagReader(src)
    with bag.BagWriter(dst) as w:
        for name, data in reader.attachments.items():
            w.add_attachment(name, "application/toml", data, reader.start_ns)
        w.add_metadata(bag.RUN_METADATA, reader.metadata.get(bag.RUN_METADATA, {}))
        for m in reader.messages():
            out = edit(m)
            if out is False:
                continue
            if isinstance(out, msgs.Message):
                w.write(m.topic, out, m.log_time_ns)
            else:
                w.write_raw(m.topic, m.msgtype, m.data, m.log_time_ns)


class Synthetic:
    """A hand-made log of ground truth and mission outputs, for grader tests."""

    def __init__(self, path: Path, scenario: Scenario) -> None:
        self.w = bag.BagWriter(path)
        self.w.add_attachment(
            SCENARIO_ATTACHMENT, "application/toml", to_toml(scenario).encode(), 1
        )
        self.t = 1_000_000_000

    def pose(self, robot: str, x: float, y: float) -> None:
        self.w.write(
            f"/ground_truth/{robot}/pose",
            msgs.PoseStamped(
                header=msgs.Header(stamp=msgs.Time.from_ns(self.t), frame_id="map"),
                pose=msgs.Pose(position=msgs.Point(x=x, y=y)),
            ),
            self.t,
        )

    def write(self, topic: str, msg: msgs.Message) -> None:
        self.w.write(topic, msg, self.t)

    def advance(self, seconds: float) -> None:
        self.t += int(seconds * 1e9)

    def close(self) -> None:
        self.w.close()
