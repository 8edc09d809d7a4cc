"""Reading image files (textures, painted maps, frames to resume), below scene/,
authoring/ and outputs/, which all decode images: OpenImageIO, with the decoders'
own stderr chatter kept off the user's terminal.
"""
from __future__ import annotations

import os

import numpy as np

from ..usd.diagnostics import one_line, usd_diagnostics


def read_float_image(path: str, max_size: int | None = None,
                     keep_8bit: bool = False, strict: bool = False) -> tuple[np.ndarray, bool]:
    """Decode an image file: ((h, w, c) float32 with row 0 at the top, is 8-bit). With
    ``keep_8bit``, an 8-bit file comes back as its uint8 codes instead.

    Raises OSError with OpenImageIO's reason when it cannot be read, when it is not a
    regular file, or when its header declares more than ``max_size`` pixels a side
    (checked before the pixels are allocated). With ``strict``, also when the decoder
    reported any error on the way: libjpeg fills a truncated JPEG with grey and only
    says so (a texture is still used; a frame to resume is not trusted).
    """
    import stat

    import OpenImageIO as oiio

    try:
        mode = os.stat(path).st_mode
    except OSError:
        raise OSError(f"cannot read image '{path}': no such file") from None
    if not stat.S_ISREG(mode):
        raise OSError(f"cannot read image '{path}': not a regular file")
    # libpng and libjpeg print their warnings on stderr themselves: keep them off the
    # user's terminal (a failure still reports OpenImageIO's reason)
    with usd_diagnostics():
        return _decode(oiio, path, max_size, keep_8bit, strict)


def _decode(oiio, path: str, max_size: int | None, keep_8bit: bool,
            strict: bool) -> tuple[np.ndarray, bool]:
    image = oiio.ImageInput.open(path)
    if image is None:
        raise OSError(f"cannot read image '{path}': {one_line(oiio.geterror()) or 'unreadable'}")
    try:
        spec = image.spec()
        if max_size is not None and max(spec.width, spec.height) > max_size:
            raise OSError(f"cannot read image '{path}': {spec.width}x{spec.height} is larger "
                          f"than {max_size} pixels a side")
        if spec.width <= 0 or spec.height <= 0 or spec.nchannels <= 0:
            raise OSError(f"cannot read image '{path}': empty image")
        eight_bit = spec.format.basetype == oiio.UINT8
        codes = keep_8bit and eight_bit
        pixels = image.read_image(0, 0, 0, spec.nchannels, oiio.UINT8 if codes else oiio.FLOAT)
        error = image.geterror()
        if pixels is None or (strict and error):
            raise OSError(f"cannot read image '{path}': {one_line(error) or 'unreadable'}")
    finally:
        image.close()
    pixels = np.asarray(pixels, np.uint8 if codes else np.float32).reshape(
        spec.height, spec.width, spec.nchannels)
    return pixels, eight_bit


#: the first bytes of each format a frame is written in
_MAGIC = {".exr": (b"\x76\x2f\x31\x01",), ".png": (b"\x89PNG\r\n\x1a\n",),
          ".jpg": (b"\xff\xd8\xff",), ".jpeg": (b"\xff\xd8\xff",),
          ".tif": (b"II*\x00", b"MM\x00*"), ".tiff": (b"II*\x00", b"MM\x00*")}


def is_complete_image(path: str, width: int, height: int,
                      channels: tuple[str, ...] | None = None) -> bool:
    """True when ``path`` is a frame as render writes it: the format its extension names
    (PNG data named .exr is not), decoding whole at width x height, and for an EXR every
    channel of ``channels`` (None: every channel a frame can hold; one missing an AOV
    asked for is not complete). ``--skip-existing`` trusts only such a file; any other is
    rendered again."""
    from .aovs import EXR_CHANNELS

    channels = EXR_CHANNELS if channels is None else channels

    ext = os.path.splitext(path)[1].lower()
    try:
        with open(path, "rb") as handle:
            head = handle.read(8)
        if ext in _MAGIC and not head.startswith(_MAGIC[ext]):
            return False
        pixels, _ = read_float_image(path, strict=True)
    except OSError:
        return False
    if pixels.shape[:2] != (height, width):
        return False
    if ext == ".exr":
        import OpenImageIO as oiio

        image = oiio.ImageInput.open(path)
        if image is None:
            return False
        try:
            found = set(image.spec().channelnames)
        finally:
            image.close()
        return set(channels) <= found
    return True
