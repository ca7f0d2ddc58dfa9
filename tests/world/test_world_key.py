"""world/world_key: the secret that makes seeded variants underivable, read from a real file
or the environment."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.core.errors import UsageError
from usar_replay.world.world_key import ENV_VAR, MIN_KEY_BYTES, WorldKey, key_from_env, load_key

SECRET = b"0123456789abcdef0123456789abcdef"


def test_the_rng_seed_depends_on_key_and_seed() -> None:
    key, other = WorldKey(SECRET), WorldKey(SECRET[::-1])
    assert key.rng_seed(7) == WorldKey(SECRET).rng_seed(7)
    assert key.rng_seed(7) != key.rng_seed(8)
    assert key.rng_seed(7) != other.rng_seed(7)
    assert 0 <= key.rng_seed(7) < 2**256 and key.rng_seed(7).bit_length() > 200


def test_the_digest_names_the_key_without_showing_it() -> None:
    key = WorldKey(SECRET)
    assert len(key.digest) == 16 and int(key.digest, 16) >= 0
    assert key.digest != WorldKey(SECRET[::-1]).digest
    assert SECRET.decode() not in repr(key) and "secret" not in repr(key)


def test_a_short_key_is_refused() -> None:
    with pytest.raises(UsageError, match=rf"at least {MIN_KEY_BYTES} bytes \(got 5\)"):
        WorldKey(b"short")


def test_load_key_strips_whitespace_and_says_when_it_cannot_read(tmp_path: Path) -> None:
    path = tmp_path / "world.key"
    path.write_bytes(b"  " + SECRET + b"\n")
    assert load_key(path) == WorldKey(SECRET)
    with pytest.raises(UsageError, match=r"--world-key .*nope: cannot read it \("):
        load_key(tmp_path / "nope")
    path.write_bytes(b"tiny\n")
    with pytest.raises(UsageError, match=r"\(got 4\)"):
        load_key(path)


def test_the_key_from_the_environment() -> None:
    assert key_from_env({}) is None
    assert key_from_env({ENV_VAR: "  \n"}) is None
    assert key_from_env({ENV_VAR: f" {SECRET.decode()}\n"}) == WorldKey(SECRET)
