"""usar-replay: run, record, replay, grade and view the two-robot US&R mission (ENPM809Y)."""

from __future__ import annotations

__version__ = "0.1.0"
