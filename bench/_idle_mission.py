"""A mission whose node subscribes to every simulator topic and does nothing (for benchmarks)."""

from usar_replay.core import contract, msgs
from usar_replay.node.node import Node


def main() -> None:
    node = Node("idle")
    for topic in contract.SIM_TOPICS:
        node.create_subscription(msgs.Message, topic, lambda m: None)
