"""Reading image files a user gives us: checked before OpenCV decodes them.

``cv2.imread`` returns None for a file it cannot read (which says nothing of why), tries to allocate whatever a
PNG or JPEG header claims (a 40-byte file can claim 30000 x 30000 pixels), and decodes a truncated JPEG with
only a warning on stderr, returning the missing part as grey. ``read_image`` reads the header first and
refuses, with one ForaNavError line naming the file: a file that is missing, empty or not an image, dimensions above
``MAX_IMAGE_PIXELS``, a PNG without its end chunk or a JPEG whose last scan has no end marker (truncated).
"""
import struct
from pathlib import Path
from typing import Optional, Tuple

import cv2
import numpy as np

from host_tools.errors import ForaNavError

MAX_IMAGE_PIXELS = 64 * 1024 * 1024  # 8192 x 8192: far above any camera here (1280x1024) or photo we train on
MAX_IMAGE_BYTES = 512 * 1024 * 1024
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
JPEG_SOI, JPEG_EOI, JPEG_SOS = b"\xff\xd8", b"\xff\xd9", b"\xff\xda"
# JPEG start-of-frame markers (0xC0-0xCF except DHT C4, JPG C8 and DAC CC) carry the frame's size
JPEG_SOF = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}


def png_size(data: bytes) -> Optional[Tuple[int, int]]:
    """(width, height) from a PNG's IHDR chunk, None when the data is not a PNG."""
    if not data.startswith(PNG_SIGNATURE) or len(data) < 24 or data[12:16] != b"IHDR":
        return None
    return struct.unpack(">II", data[16:24])


def jpeg_size(data: bytes) -> Optional[Tuple[int, int]]:
    """(width, height) from a JPEG's first start-of-frame marker, None when there is none."""
    if not data.startswith(JPEG_SOI):
        return None
    pos = 2
    while pos + 4 <= len(data):
        if data[pos] != 0xFF:
            return None
        marker = data[pos + 1]
        if marker == 0xFF:  # fill byte
            pos += 1
            continue
        if marker in (0x01,) or 0xD0 <= marker <= 0xD7:  # markers without a length
            pos += 2
            continue
        length = struct.unpack(">H", data[pos + 2:pos + 4])[0]
        if marker in JPEG_SOF and pos + 9 <= len(data):
            height, width = struct.unpack(">HH", data[pos + 5:pos + 9])
            return width, height
        if marker == 0xDA:  # start of scan before any frame header
            return None
        pos += 2 + length
    return None


def check_image_bytes(data: bytes, name: str) -> None:
    """Raise ForaNavError when the bytes claim a huge image or are a truncated PNG/JPEG (other formats pass)."""
    size = png_size(data) or jpeg_size(data)
    if size is not None:
        width, height = size
        if width == 0 or height == 0:
            raise ForaNavError("%s: image header claims %dx%d pixels" % (name, width, height))
        if width * height > MAX_IMAGE_PIXELS:
            raise ForaNavError("%s: image header claims %dx%d pixels, more than %d Mpx"
                               % (name, width, height, MAX_IMAGE_PIXELS // (1024 * 1024)))
    if data.startswith(PNG_SIGNATURE) and data.rfind(b"IEND") < 0:
        raise ForaNavError("%s: truncated PNG (no IEND chunk)" % name)
    if data.startswith(JPEG_SOI) and data.rfind(JPEG_EOI) < data.rfind(JPEG_SOS):
        raise ForaNavError("%s: truncated JPEG (its last scan has no end-of-image marker)" % name)


def read_image(path: str | Path) -> np.ndarray:
    """A BGR image (uint8, 3 channels) from a file, checked as the module docstring says."""
    return read_image_file(path)[1]


def read_image_file(path: str | Path) -> tuple[bytes, np.ndarray]:
    """The file's bytes and its BGR image (uint8, 3 channels), checked as the module docstring says (the bytes
    for a checksum of exactly what was decoded)."""
    path = Path(path)
    try:
        if path.is_dir():
            raise ForaNavError("%s: is a folder, expected an image" % path)
        with open(path, "rb") as handle:
            data = handle.read(MAX_IMAGE_BYTES + 1)
    except OSError as err:
        raise ForaNavError("%s: cannot read image: %s" % (path, err.strerror or err))
    if len(data) > MAX_IMAGE_BYTES:
        raise ForaNavError("%s: image file larger than %d MiB" % (path, MAX_IMAGE_BYTES // (1024 * 1024)))
    if not data:
        raise ForaNavError("%s: empty file (0 bytes), not an image" % path)
    check_image_bytes(data, str(path))
    try:
        image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    except cv2.error:  # OpenCV asserts on some damaged files instead of returning None
        image = None
    if image is None:
        raise ForaNavError("%s: not an image OpenCV can decode" % path)
    return data, image
