"""The world key: a secret that makes ``--seed`` variants underivable from installed code.

Why: a seeded variant (:func:`usar_replay.world.variants.make_variant`) is a pure function of
the base world and the seed, and the package is installed on every student's machine. A mission
reads its lookup targets as parameters, tries ``make_variant(course_world(), s)`` for every
seed until the targets match, and so knows where every marker is without detecting anything.
With a key, the variant generator's random stream is seeded by ``HMAC-SHA256(key, seed)``
instead of the seed: without the key, the seed says nothing about the world.

* The key is a file of at least :data:`MIN_KEY_BYTES` bytes (``--world-key FILE``), or the
  environment variable :data:`ENV_VAR` holding the key itself (the autograder's environment).
  Make one with ``head -c 32 /dev/urandom | base64 > world.key``.
* The log records only :attr:`WorldKey.digest`, a short HMAC of a fixed label: it tells two
  keys apart (which key made this world?) and says nothing about the key or the worlds.
* Without a key, every world and every byte is what it was before keys existed.

Pure: the only I/O is :func:`load_key` reading the file it is given.
"""

from __future__ import annotations

import hashlib
import hmac
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from usar_replay.core.errors import UsageError

__all__ = ["ENV_VAR", "MIN_KEY_BYTES", "WorldKey", "key_from_env", "load_key"]

ENV_VAR = "USAR_WORLD_KEY"
"""The environment variable that may hold the key (the key's text, not a path)."""
MIN_KEY_BYTES = 16
"""A shorter key could be guessed by trying keys against a world's targets."""
_SEED_LABEL = b"usar-replay world variant seed "
_DIGEST_LABEL = b"usar-replay world key digest"


@dataclass(frozen=True, slots=True)
class WorldKey:
    """A secret mixed into the variant generator; its ``repr`` never shows the secret."""

    secret: bytes = field(repr=False)

    def __post_init__(self) -> None:
        if len(self.secret) < MIN_KEY_BYTES:
            raise UsageError(
                f"a world key must be at least {MIN_KEY_BYTES} bytes (got {len(self.secret)}); "
                "make one with: head -c 32 /dev/urandom | base64 > world.key"
            )

    def rng_seed(self, seed: int) -> int:
        """The seed of ``numpy.random.default_rng`` for variant ``seed``: HMAC-SHA256(key,
        label + seed) as a 256-bit integer."""
        mac = hmac.new(self.secret, _SEED_LABEL + str(seed).encode(), hashlib.sha256)
        return int.from_bytes(mac.digest(), "big")

    @property
    def digest(self) -> str:
        """16 hex digits naming the key (an HMAC of a fixed label): safe to record."""
        return hmac.new(self.secret, _DIGEST_LABEL, hashlib.sha256).hexdigest()[:16]


def load_key(path: str | os.PathLike[str]) -> WorldKey:
    """The key in ``path`` (its bytes, surrounding whitespace removed); :class:`UsageError`
    when it cannot be read or is too short."""
    try:
        data = Path(path).read_bytes().strip()
    except OSError as err:
        raise UsageError(f"--world-key {path}: cannot read it ({err.strerror})") from None
    return WorldKey(data)


def key_from_env(environ: Mapping[str, str] | None = None) -> WorldKey | None:
    """The key in :data:`ENV_VAR` (``os.environ`` by default); None when it is unset or empty."""
    text = (os.environ if environ is None else environ).get(ENV_VAR, "").strip()
    return WorldKey(text.encode()) if text else None
