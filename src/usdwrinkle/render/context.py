"""One headless OpenGL 4.3+ context (compute shaders) through EGL.

On a machine without a GPU, Mesa's llvmpipe provides GL 4.5; on a GPU machine
the vendor's EGL gives the same API, so the same code runs on both.
"""
from __future__ import annotations

import ctypes
import functools
import os
from contextlib import contextmanager, nullcontext

from ..process.errors import GLContextError
from ..process.signals import signals_held

REQUIRED_VERSION = 430


def is_software_renderer(gl_renderer: str) -> bool:
    """Mesa's software rasterisers (llvmpipe, softpipe): the CPU does the GPU's work."""
    return "llvmpipe" in gl_renderer or "softpipe" in gl_renderer
_context = None
#: libEGL (current()) and the EGL handle of the process's context, while it is EGL's
_egl = None
_own = None
#: EGL_DRAW, EGL_READ (EGL/egl.h)
_EGL_DRAW, _EGL_READ = 0x3059, 0x305A


def create_context(backend: str | None = None):
    """Create (once) and return the process's moderngl context.

    Raises GLContextError with a one-line explanation when no GL 4.3 context
    can be made.
    """
    global _context, _egl, _own
    if _context is not None:
        return _context
    try:
        import moderngl
    except ImportError as exc:  # pragma: no cover - a broken install
        raise GLContextError(f"moderngl is not installed ({exc})") from None
    backend = backend or os.environ.get("USDWRINKLE_GL_BACKEND", "egl")
    options = {}
    device = os.environ.get("USDWRINKLE_EGL_DEVICE", "").strip()
    if device and backend == "egl":  # which GPU of a multi-GPU node (EGL's device list)
        if not (device.isascii() and device.isdigit()):
            raise GLContextError(f"USDWRINKLE_EGL_DEVICE must be a device index (0, 1, ...), "
                                 f"not '{device}'")
        options["device_index"] = int(device)
    try:
        # the driver's threads start here and inherit the held signals for good
        with signals_held():
            ctx = moderngl.create_standalone_context(backend=backend,
                                                     require=REQUIRED_VERSION, **options)
    except Exception as exc:  # moderngl raises plain Exceptions from glcontext
        detail = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise GLContextError(
            f"cannot create an OpenGL {REQUIRED_VERSION // 100}.{REQUIRED_VERSION % 100 // 10} "
            f"context through {backend.upper()} ({detail}); usdwrinkle needs compute shaders: "
            "install Mesa's EGL and llvmpipe (Debian: libegl1 libgl1-mesa-dri) or a GPU driver "
            "with EGL") from None
    if ctx.version_code < REQUIRED_VERSION:
        version = ctx.version_code
        ctx.release()
        raise GLContextError(
            f"the OpenGL context is version {version // 100}.{version % 100 // 10}, but "
            "usdwrinkle needs 4.3 or newer (compute shaders); update Mesa or the GPU driver")
    _context = ctx
    _egl = _egl_library(backend)
    _own = _egl.eglGetCurrentContext() if _egl is not None else None
    return ctx


def current(ctx):
    """A block whose GL calls go to ``ctx``, when it is the process's own context
    (create_context, through EGL). GL calls go to the thread's current context, not to
    the context object that makes them, and another context may have been made current
    since ours was: a second standalone context in a Python session (a bake then wrote
    zeros for every point of its fine mesh, silently), or an EGL host's. Ours is made
    current for the block, and the context that was current before is current again after
    it; where ours is current already the block changes nothing (so blocks nest). A
    context the caller hands in (the paint window's, Qt's) is the caller's to make
    current: left as it is."""
    if ctx is None or ctx is not _context or _egl is None:
        return nullcontext()
    return _made_current(ctx)


def in_own_context(function):
    """A function or method whose first argument holds the context its GL calls go to
    (``.ctx``: an engine): it runs inside current(first.ctx)."""
    @functools.wraps(function)
    def call(first, *args, **kwargs):
        with current(first.ctx):
            return function(first, *args, **kwargs)
    return call


@contextmanager
def _made_current(ctx):
    before = _egl.eglGetCurrentContext()
    if before == _own:
        yield
        return
    if before:
        surfaces = (_egl.eglGetCurrentDisplay(), _egl.eglGetCurrentSurface(_EGL_DRAW),
                    _egl.eglGetCurrentSurface(_EGL_READ))
    ctx.__enter__()  # moderngl: eglMakeCurrent with our context
    try:
        yield
    finally:
        if before:  # give the thread its context back
            _egl.eglMakeCurrent(*surfaces, before)
        # with none current before, ours stays current, as it is after create_context


def _egl_library(backend: str):
    """libEGL, with the prototypes current() calls, where the context is EGL's (None
    otherwise, or where it cannot be loaded)."""
    if backend != "egl":
        return None
    try:
        lib = ctypes.CDLL("libEGL.so.1")
    except OSError:
        return None
    for name in ("eglGetCurrentContext", "eglGetCurrentDisplay"):
        getattr(lib, name).restype = ctypes.c_void_p
        getattr(lib, name).argtypes = []
    lib.eglGetCurrentSurface.restype = ctypes.c_void_p
    lib.eglGetCurrentSurface.argtypes = [ctypes.c_int]
    lib.eglMakeCurrent.restype = ctypes.c_uint
    lib.eglMakeCurrent.argtypes = [ctypes.c_void_p] * 4
    return lib


def release_context() -> None:
    """Release the process's context (tests and long-running hosts)."""
    global _context, _egl, _own
    if _context is not None:
        from .shaders import release_programs

        release_programs(_context)
        _context.release()
        _context = _egl = _own = None


def renderer_info() -> dict:
    ctx = create_context()
    return {"renderer": ctx.info.get("GL_RENDERER", "?"),
            "version": ctx.info.get("GL_VERSION", "?"),
            "vendor": ctx.info.get("GL_VENDOR", "?")}
