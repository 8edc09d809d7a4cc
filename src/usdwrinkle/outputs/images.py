"""Write render buffers with OpenImageIO.

EXR: float channels R,G,B,A, wrinkle.height, wrinkle.amplitude, N.X,N.Y,N.Z, Z.
PNG/JPEG/TIFF: the 8-bit sRGB beauty (RGBA; RGB over black for JPEG).
"""
from __future__ import annotations

import contextlib
import functools
import os
import shutil
import tempfile

import numpy as np

from ..colour import srgb_encode
from ..errors import UsdWrinkleError
from ..scene.diagnostics import one_line, usd_diagnostics
from .atomic import atomic_path, sweep_dead

FLOAT_FORMATS = (".exr",)
EIGHT_BIT_FORMATS = (".png", ".jpg", ".jpeg", ".tif", ".tiff")
EXR_ORDER = ("color", "wrinkle.height", "wrinkle.amplitude", "normal", "depth")
#: EXR compressions offered by --exr-compression (OpenEXR's names)
EXR_COMPRESSIONS = ("zip", "zips", "piz", "dwaa", "none")
#: the AOVs that --exr-half stores as half float; depth and the wrinkle fields stay float
HALF_AOVS = ("color", "normal")


def aovs_for(path: str) -> tuple:
    """The render buffers a file format stores."""
    return EXR_ORDER if check_format(path) in FLOAT_FORMATS else ("color",)


def check_format(path: str) -> str:
    ext = os.path.splitext(path)[1].lower()
    if ext not in FLOAT_FORMATS + EIGHT_BIT_FORMATS:
        raise UsdWrinkleError(
            f"unsupported image format '{ext or path}': use .exr, .png, .jpg or .tif")
    return ext


def read_float_image(path: str, max_size: int | None = None,
                     keep_8bit: bool = False) -> tuple[np.ndarray, bool]:
    """Decode an image file: ((h, w, c) float32 with row 0 at the top, is 8-bit). With
    ``keep_8bit``, an 8-bit file comes back as its uint8 codes instead.

    Raises OSError with OpenImageIO's reason when it cannot be read, when it is not a
    regular file, or when its header declares more than ``max_size`` pixels a side
    (checked before the pixels are allocated).
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
        return _decode(oiio, path, max_size, keep_8bit)


def _decode(oiio, path: str, max_size: int | None, keep_8bit: bool) -> tuple[np.ndarray, bool]:
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
        if pixels is None:
            raise OSError(f"cannot read image '{path}': {one_line(image.geterror())}")
    finally:
        image.close()
    pixels = np.asarray(pixels, np.uint8 if codes else np.float32).reshape(
        spec.height, spec.width, spec.nchannels)
    return pixels, eight_bit


def is_complete_image(path: str, width: int, height: int) -> bool:
    """True when ``path`` decodes whole at width x height (``--skip-existing`` trusts only
    such a file; a truncated or foreign one is rendered again)."""
    try:
        pixels, _ = read_float_image(path)
    except OSError:
        return False
    return pixels.shape[:2] == (height, width)


SCRATCH_PREFIX = ".usdwrinkle-frame."


@functools.cache
def _scratch_folder() -> str:
    """Where frames are encoded before they are copied to their output: memory (/dev/shm)
    where there is one, so that a full output disk fails in our copy, with an error,
    never inside an image library. Found once per process, when scratch frames of
    processes that no longer run are removed too."""
    shm = "/dev/shm"
    folder = shm if os.path.isdir(shm) and os.access(shm, os.W_OK | os.X_OK) \
        else tempfile.gettempdir()
    _sweep_scratch(folder)
    return folder


def _sweep_scratch(folder: str) -> None:
    """Remove scratch frames of processes that no longer run (a SIGKILLed farm worker
    never reaches its cleanup, and /dev/shm is memory)."""
    sweep_dead(folder, SCRATCH_PREFIX, os.unlink)


def _check_finite(buffers: dict, aovs) -> None:
    """No NaN or Inf reaches an image (Z may be +Inf where nothing was hit)."""
    for aov in aovs:
        pixels = buffers[aov].pixels
        bad = np.isnan(pixels) if aov == "depth" else ~np.isfinite(pixels)
        if bad.any():
            raise UsdWrinkleError(
                f"the frame's {aov} has non-finite pixels (NaN or Inf); a camera, light, "
                "transform or wrinkle value of the scene is out of range")


def encode_file(scratch: str, spec, pixels: np.ndarray, path: str) -> None:
    """Encode ``pixels`` to the file ``scratch`` with OpenImageIO; errors name ``path``,
    the output it stands in for."""
    import OpenImageIO as oiio

    out = oiio.ImageOutput.create(scratch)
    if out is None or not out.open(scratch, spec):
        raise UsdWrinkleError(f"cannot write image '{path}': {one_line(oiio.geterror())}")
    ok = out.write_image(pixels)
    error = out.geterror()
    closed = out.close()
    if not (ok and closed):
        reason = one_line(error or out.geterror() or oiio.geterror()) or "unknown reason"
        raise UsdWrinkleError(f"cannot write image '{path}': {reason}")


def write_image(path: str, buffers: dict, compression: str = "zip", half: bool = False) -> None:
    """Write one frame's render buffers to ``path``, atomically and completely.

    EXR: ``compression`` (EXR_COMPRESSIONS) and ``half`` (colour and normals as half
    float, as compositing usually keeps them; depth and the wrinkle fields stay float).

    The frame is encoded in memory, copied beside ``path`` and renamed only once the
    copy has the encoded size: a full disk or a failing close is an error, and never
    leaves a truncated frame under the output name.
    """
    import OpenImageIO as oiio

    ext = check_format(path)
    _check_finite(buffers, EXR_ORDER if ext in FLOAT_FORMATS else ("color",))
    if ext in FLOAT_FORMATS:
        planes, names = [], []
        for aov in EXR_ORDER:
            buf = buffers[aov]
            planes.append(buf.pixels)
            names.extend(buf.channel_names)
        pixels = np.ascontiguousarray(np.concatenate(planes, axis=2), np.float32)
        spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], "float")
        spec.channelnames = tuple(names)
        spec.alpha_channel = 3
        spec.z_channel = names.index("Z")
        if half:
            half_names = {n for aov in HALF_AOVS for n in buffers[aov].channel_names}
            spec.channelformats = tuple(oiio.TypeDesc("half" if n in half_names else "float")
                                        for n in names)
        spec.attribute("compression", compression)
    else:
        color = buffers["color"].pixels  # premultiplied by alpha
        alpha = np.clip(color[..., 3:4], 0, 1)
        if ext in (".jpg", ".jpeg"):
            pixels = srgb_encode(color[..., :3])  # over black
        else:
            # PNG and TIFF store straight (unassociated) alpha
            straight = np.divide(color[..., :3], alpha, out=np.zeros_like(color[..., :3]),
                                 where=alpha > 0)
            pixels = np.concatenate([srgb_encode(straight), alpha], axis=2)
        pixels = np.ascontiguousarray(np.round(pixels * 255), np.uint8)
        spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], "uint8")
        if pixels.shape[2] == 4:
            spec.alpha_channel = 3
            spec.attribute("oiio:UnassociatedAlpha", 1)  # already straight: leave it
    fd, scratch = tempfile.mkstemp(prefix=f"{SCRATCH_PREFIX}{os.getpid()}.", suffix=ext,
                                   dir=_scratch_folder())
    os.close(fd)
    try:
        encode_file(scratch, spec, pixels, path)
        size = os.path.getsize(scratch)

        def complete(tmp: str) -> None:
            if os.path.getsize(tmp) != size:
                raise OSError(28, f"only {os.path.getsize(tmp)} of {size} bytes were written")

        with atomic_path(path, verify=complete) as tmp:
            shutil.copyfile(scratch, tmp)
    finally:
        with contextlib.suppress(OSError):
            os.unlink(scratch)
