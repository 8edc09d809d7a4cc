"""Write render buffers with OpenImageIO.

EXR: float channels R,G,B,A, wrinkle.height, wrinkle.amplitude, N.X,N.Y,N.Z, Z.
PNG/JPEG/TIFF: the 8-bit sRGB beauty (RGBA; RGB over black for JPEG).
"""
from __future__ import annotations

import os

import numpy as np

from ..errors import UsdWrinkleError
from .atomic import atomic_path

FLOAT_FORMATS = (".exr",)
EIGHT_BIT_FORMATS = (".png", ".jpg", ".jpeg", ".tif", ".tiff")
EXR_ORDER = ("color", "wrinkle.height", "wrinkle.amplitude", "normal", "depth")


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    c = np.clip(linear, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def aovs_for(path: str) -> tuple:
    """The render buffers a file format stores."""
    return EXR_ORDER if check_format(path) in FLOAT_FORMATS else ("color",)


def check_format(path: str) -> str:
    ext = os.path.splitext(path)[1].lower()
    if ext not in FLOAT_FORMATS + EIGHT_BIT_FORMATS:
        raise UsdWrinkleError(
            f"unsupported image format '{ext or path}': use .exr, .png, .jpg or .tif")
    return ext


def read_float_image(path: str) -> tuple[np.ndarray, bool]:
    """Decode an image file: ((h, w, c) float32 with row 0 at the top, is 8-bit).

    Raises OSError with OpenImageIO's reason when it cannot be read.
    """
    import OpenImageIO as oiio

    if not os.path.isfile(path):
        raise OSError(f"cannot read image '{path}': no such file")
    image = oiio.ImageInput.open(path)
    if image is None:
        raise OSError(f"cannot read image '{path}': {oiio.geterror().strip() or 'unreadable'}")
    try:
        spec = image.spec()
        pixels = image.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        if pixels is None:
            raise OSError(f"cannot read image '{path}': {image.geterror().strip()}")
    finally:
        image.close()
    pixels = np.asarray(pixels, np.float32).reshape(spec.height, spec.width, spec.nchannels)
    return pixels, spec.format.basetype == oiio.UINT8


def write_image(path: str, buffers: dict) -> None:
    """Write one frame's render buffers to ``path``, atomically."""
    import OpenImageIO as oiio

    ext = check_format(path)
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
        spec.attribute("compression", "zip")
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
    with atomic_path(path) as tmp:
        out = oiio.ImageOutput.create(tmp)
        if out is None or not out.open(tmp, spec):
            raise UsdWrinkleError(f"cannot write image '{path}': {oiio.geterror()}")
        ok = out.write_image(pixels)
        out.close()
        if not ok:
            raise UsdWrinkleError(f"cannot write image '{path}': {out.geterror()}")
