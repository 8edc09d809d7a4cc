"""Write rendered frames: EXR with OpenEXR's own binding, 8-bit formats with OpenImageIO.

EXR: channels R,G,B,A, wrinkle.height, wrinkle.amplitude, N.X,N.Y,N.Z, Z (render
``--aovs``: those of the AOVs asked for); colour and normals half float by default, the
rest float.
PNG/JPEG/TIFF: the 8-bit sRGB beauty (RGBA; RGB over black for JPEG).

A frame arrives as an aovs.ResolvedImage, already in the file's layout (the
resolve pass made it on the GPU: layout_for); image_from_buffers makes the same from
float RenderBuffers in numpy. OpenEXR's binding writes the planes as they are; through
OpenImageIO, mixed half/float channels took 79 ms to encode a 640x360 CesiumMan frame on
one core against 14 ms (docs/benchmarks.md, "EXR encoders").
"""
from __future__ import annotations

import contextlib
import functools
import os
import shutil
import tempfile
import threading

import numpy as np

from ..images.aovs import AOV_BLOCKS, HALF_CHANNELS, ImageLayout, ResolvedImage
from ..images.colour import srgb_encode
from ..process.errors import UsdWrinkleError
from ..usd.diagnostics import one_line
from .atomic import atomic_path, sweep_dead, write_error

FLOAT_FORMATS = (".exr",)
EIGHT_BIT_FORMATS = (".png", ".jpg", ".jpeg", ".tif", ".tiff")
#: EXR compressions offered by --exr-compression (OpenEXR's names)
EXR_COMPRESSIONS = ("zip", "zips", "piz", "dwaa", "none")
#: libpng's row filter for frames (PNG_FILTER_UP) and their zlib level
PNG_FILTER_UP = 0x20
PNG_FRAME_COMPRESSION = 1
#: OpenEXR's own encode threads per file where no caller says: 0, the file compressed in
#: the calling thread. A render's frames take outputs/writer.exr_threads, chosen per node
EXR_THREADS = 0


def layout_for(path: str, half: bool = True, aovs: tuple[str, ...] = AOV_BLOCKS) -> ImageLayout:
    """The layout a frame written to ``path`` is read back in: an EXR's planes of
    ``aovs`` (colour and normals half float with ``half``), else 8-bit codes (the
    beauty: stored_aovs refuses other AOVs for them)."""
    ext = check_format(path)
    if ext in FLOAT_FORMATS:
        return ImageLayout("exr", aovs=tuple(aovs), half=half)
    return ImageLayout("8bit", aovs=("color",), over_black=ext in (".jpg", ".jpeg"))


def stored_aovs(path: str, aovs: tuple[str, ...] | None) -> tuple[str, ...]:
    """The AOVs a frame written to ``path`` stores: ``aovs`` (None: every one) for an EXR;
    the beauty alone for an 8-bit file, which refuses any other AOV asked for."""
    ext = check_format(path)
    if ext in FLOAT_FORMATS:
        return AOV_BLOCKS if aovs is None else tuple(aovs)
    if aovs is not None and tuple(aovs) != ("color",):
        raise UsdWrinkleError(f"`aovs` {','.join(aovs)}: a {ext} frame stores the colour "
                              "alone (`aovs` color); write .exr for the other AOVs")
    return ("color",)


def image_from_buffers(buffers: dict, layout: ImageLayout) -> ResolvedImage:
    """The frame of float RenderBuffers in ``layout``, in numpy: what the resolve pass
    makes on the GPU (for a caller that holds RenderBuffers, and as its test oracle)."""
    color = buffers["color"].pixels  # premultiplied by alpha
    height, width = color.shape[:2]
    if layout.kind == "exr":
        planes = {}
        for aov in (aov for aov in AOV_BLOCKS if aov in layout.aovs):
            buf = buffers[aov]
            for index, name in enumerate(buf.channel_names):
                plane = np.ascontiguousarray(buf.pixels[..., index], np.float32)
                planes[name] = plane.astype(np.float16) \
                    if layout.half and name in HALF_CHANNELS else plane
        bad = sum(int(np.count_nonzero(np.isnan(p) if name == "Z" else ~np.isfinite(p)))
                  for name, p in planes.items())
    else:
        alpha = np.clip(color[..., 3:4], 0, 1)
        if layout.over_black:
            rgba = np.concatenate([srgb_encode(color[..., :3]), np.ones_like(alpha)], axis=2)
        else:  # straight (unassociated) alpha, as PNG and TIFF store it
            straight = np.divide(color[..., :3], alpha, out=np.zeros_like(color[..., :3]),
                                 where=alpha > 0)
            rgba = np.concatenate([srgb_encode(straight), alpha], axis=2)
        planes = {"RGBA": np.round(rgba * 255).astype(np.uint8)}
        bad = int(np.count_nonzero(~np.isfinite(color)))
    return ResolvedImage(layout, width, height, planes, bad)


def check_format(path: str) -> str:
    ext = os.path.splitext(path)[1].lower()
    if ext not in FLOAT_FORMATS + EIGHT_BIT_FORMATS:
        raise UsdWrinkleError(
            f"unsupported image format '{ext or path}': use .exr, .png, .jpg or .tif")
    return ext


SCRATCH_PREFIX = ".usdwrinkle-frame."


@contextlib.contextmanager
def memory_file(suffix: str):
    """Yield the path of an empty file that lives in memory, for an image library to
    encode into; removed when the block ends.

    On Linux it is an anonymous memory file (memfd_create, opened by its /proc/self/fd
    path): no file system holds it, so neither a small /dev/shm nor a full output disk
    can cut an encode short. That matters because the libraries do not all say so when
    a write fails: libpng leaves a truncated PNG and reports success, and libjpeg ends
    the process. Elsewhere it is a temporary file in the system's temporary folder.
    """
    if hasattr(os, "memfd_create") and os.path.isdir(f"/proc/{os.getpid()}/fd"):
        fd = os.memfd_create(f"usdwrinkle-frame{suffix}", os.MFD_CLOEXEC)
        try:
            yield f"/proc/{os.getpid()}/fd/{fd}"
        finally:
            os.close(fd)
        return
    folder = _scratch_folder()
    fd, scratch = tempfile.mkstemp(prefix=f"{SCRATCH_PREFIX}{os.getpid()}.", suffix=suffix,
                                   dir=folder)
    os.close(fd)
    try:
        yield scratch
    finally:
        with contextlib.suppress(OSError):
            os.unlink(scratch)


@functools.cache
def _scratch_folder() -> str:
    """Where memory_file encodes where there are no anonymous memory files: the system's
    temporary folder, found once per process, when scratch files of processes that no
    longer run are removed too (a SIGKILLed farm worker never reaches its cleanup)."""
    folder = tempfile.gettempdir()
    sweep_dead(folder, SCRATCH_PREFIX, os.unlink)
    return folder


def copy_complete(source: str, path: str, atomic: bool = True, shown: str | None = None) -> None:
    """Copy the encoded file ``source`` to ``path``; the copy is checked for its full size
    before it takes the name ``path`` (atomically, a temporary file beside it renamed,
    unless ``atomic`` is off for a file in a staging folder), so a full disk is the
    one-line error and never a truncated file under the output's name. Errors name
    ``shown`` (default ``path``): a staged file's final path."""
    size = os.path.getsize(source)

    def complete(tmp: str) -> None:
        if os.path.getsize(tmp) != size:
            raise OSError(28, f"only {os.path.getsize(tmp)} of {size} bytes were written")

    if atomic:
        with atomic_path(path, verify=complete) as tmp:
            shutil.copyfile(source, tmp)
        return
    try:
        shutil.copyfile(source, path)
        complete(path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.unlink(path)
        raise write_error(shown or path, exc) from None


def _check_finite(image: ResolvedImage) -> None:
    """No NaN or Inf reaches an image (Z may be +Inf where nothing was hit)."""
    if image.bad:
        values = "value" if image.bad == 1 else "values"
        raise UsdWrinkleError(
            f"the frame has {image.bad} non-finite {values} (NaN or Inf); a camera, light, "
            "transform or wrinkle value of the scene is out of range")


def encode_file(scratch: str, spec, pixels: np.ndarray, path: str) -> None:
    """Encode ``pixels`` to the file ``scratch`` with OpenImageIO; errors name ``path``,
    the output it stands in for."""
    import OpenImageIO as oiio

    # the format is the output's: ``scratch`` may be a memory file with no extension
    out = oiio.ImageOutput.create(os.path.splitext(path)[1].lstrip(".").lower())
    if out is None or not out.open(scratch, spec):
        raise UsdWrinkleError(f"cannot write image '{path}': {one_line(oiio.geterror())}")
    ok = out.write_image(pixels)
    error = out.geterror()
    closed = out.close()
    if not (ok and closed):
        reason = one_line(error or out.geterror() or oiio.geterror()) or "unknown reason"
        raise UsdWrinkleError(f"cannot write image '{path}': {reason}")


def encode_frame(scratch: str, image: ResolvedImage, path: str,
                 compression: str = "zip", exr_threads: int = EXR_THREADS) -> None:
    """Encode one frame to the file ``scratch``: EXR with OpenEXR (its chunks compressed
    on ``exr_threads`` of its own threads; 0: in this thread), 8-bit formats with
    OpenImageIO."""
    if image.layout.kind == "exr":
        _encode_exr(scratch, image, path, compression, exr_threads)
        return
    import OpenImageIO as oiio

    pixels = image.planes["RGBA"]
    if image.layout.over_black:
        pixels = np.ascontiguousarray(pixels[..., :3])
    spec = oiio.ImageSpec(image.width, image.height, pixels.shape[2], "uint8")
    if pixels.shape[2] == 4:
        spec.alpha_channel = 3
        spec.attribute("oiio:UnassociatedAlpha", 1)  # already straight: leave it
    if path.lower().endswith(".png"):
        # libpng's default tries every row filter at zlib level 6: 18 ms for a 960x540
        # frame; the "up" filter at level 1 takes 5.2 ms for files 22% larger (a render
        # node's CPU is shared with llvmpipe's draw; docs/benchmarks.md)
        spec.attribute("png:filter", PNG_FILTER_UP)
        spec.attribute("png:compressionLevel", PNG_FRAME_COMPRESSION)
    encode_file(scratch, spec, pixels, path)


def _encode_exr(scratch: str, image: ResolvedImage, path: str, compression: str,
                threads: int) -> None:
    import OpenEXR

    from .. import __version__

    header = {"compression": getattr(OpenEXR, _EXR_COMPRESSION[compression]),
              "type": OpenEXR.scanlineimage, "software": f"usdwrinkle {__version__}"}
    if threads > 0:
        _exr_pool(threads)
    try:
        with OpenEXR.File(header, dict(image.planes), threads) as exr:
            exr.write(scratch)
    except (RuntimeError, ValueError, TypeError) as exc:  # the binding's, with the reason
        raise UsdWrinkleError(f"cannot write image '{path}': {one_line(str(exc))}") from None


_pool_lock = threading.Lock()


def _exr_pool(threads: int) -> None:
    """Grow OpenEXR's global thread pool (which every file's own threads come from, and
    which starts empty) to at least the cores, once; a file asks it for ``threads``."""
    import OpenEXR

    from .writer import cores

    with _pool_lock:
        wanted = max(threads, cores())
        if OpenEXR.global_thread_count() < wanted:
            OpenEXR.set_global_thread_count(wanted)


#: --exr-compression -> the OpenEXR binding's constant
_EXR_COMPRESSION = {"zip": "ZIP_COMPRESSION", "zips": "ZIPS_COMPRESSION",
                    "piz": "PIZ_COMPRESSION", "dwaa": "DWAA_COMPRESSION",
                    "none": "NO_COMPRESSION"}


def write_image(path: str, image, compression: str = "zip", half: bool = True,
                exr_threads: int = EXR_THREADS) -> None:
    """Write one frame to ``path``, atomically and completely.

    ``image``: a ResolvedImage in ``layout_for(path)``'s kind, or a dict of float
    RenderBuffers (converted here, colour and normals of an EXR half float with
    ``half``). EXR: ``compression`` (EXR_COMPRESSIONS).

    The frame is encoded in memory (memory_file), copied beside ``path`` and renamed
    only once the copy has the encoded size: a full disk or a failing close is an
    error, and never leaves a truncated frame under the output name.
    """
    ext = check_format(path)
    if isinstance(image, dict):
        image = image_from_buffers(image, layout_for(path, half))
    _check_finite(image)
    with memory_file(ext) as scratch:
        encode_frame(scratch, image, path, compression, exr_threads)
        copy_complete(scratch, path)
