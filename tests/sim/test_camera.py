"""sim/camera: frames compressed as they are recorded: lossless PNG, deterministic bytes, and
the previous frame's bytes handed back only for equal pixels."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from usar_replay.sim import camera
from usar_replay.sim.camera import encode_image


def _frame(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    frame = np.full((120, 160, 3), 200, np.uint8)
    frame[30:90, 40:120] = rng.integers(0, 255, (60, 80, 3), dtype=np.uint8)
    return frame


def test_png_is_lossless_and_jpeg_is_smaller_and_close() -> None:
    frame = _frame(1)
    png = encode_image(frame, "png")
    assert png.startswith(b"\x89PNG")
    back = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    assert np.array_equal(back, frame)
    flat = np.full((120, 160, 3), 90, np.uint8)
    jpeg = encode_image(flat, "jpeg")
    assert jpeg.startswith(b"\xff\xd8")
    assert len(encode_image(frame, "jpeg")) < len(png)  # lossy: smaller on a noisy frame
    decoded = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
    assert int(np.abs(decoded.astype(int) - 90).max()) <= 2


@pytest.mark.parametrize("fmt", ["png", "jpeg"])
def test_equal_pixels_give_the_bytes_a_fresh_encode_gives(fmt: str) -> None:
    """(Moved from tests/world/test_detect.py, on a drawn frame instead of a rendered one.)"""
    pixels = _frame(2)
    first = encode_image(pixels, fmt)
    again = encode_image(pixels.copy(), fmt)  # equal pixels, another array: from the memory
    camera._ENCODED.last = None  # forget it, as a fresh process would
    assert again == first == encode_image(pixels.copy(), fmt)
    other = pixels.copy()
    other[0, 0, 0] ^= 1  # one changed bit is a new frame
    assert encode_image(other, fmt) != first or fmt == "jpeg"
    assert encode_image(pixels, "jpeg", 50) != encode_image(pixels, "jpeg", 95)


def test_a_frame_changed_in_place_after_encoding_is_encoded_again() -> None:
    frame = _frame(4)
    first = encode_image(frame)
    frame[0, 0] = (0, 0, 0)  # the memory holds a copy, never the caller's array
    changed = encode_image(frame)
    assert changed != first
    pixel = cv2.imdecode(np.frombuffer(changed, np.uint8), cv2.IMREAD_COLOR)[0, 0]
    assert pixel.tolist() == [0, 0, 0]
    assert encode_image(frame, png_level=1) != changed  # other settings: other bytes


def test_an_unknown_format_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown image format 'gif'"):
        encode_image(_frame(3), "gif")
