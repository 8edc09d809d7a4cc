"""One headless OpenGL 4.3+ context (compute shaders) through EGL.

On a machine without a GPU, Mesa's llvmpipe provides GL 4.5; on a GPU machine
the vendor's EGL gives the same API, so the same code runs on both.
"""
from __future__ import annotations

import os

from ..process.errors import GLContextError
from ..process.signals import signals_held

REQUIRED_VERSION = 430


def is_software_renderer(gl_renderer: str) -> bool:
    """Mesa's software rasterisers (llvmpipe, softpipe): the CPU does the GPU's work."""
    return "llvmpipe" in gl_renderer or "softpipe" in gl_renderer
_context = None


def create_context(backend: str | None = None):
    """Create (once) and return the process's moderngl context.

    Raises GLContextError with a one-line explanation when no GL 4.3 context
    can be made.
    """
    global _context
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
    return ctx


def release_context() -> None:
    """Release the process's context (tests and long-running hosts)."""
    global _context
    if _context is not None:
        from .shaders import release_programs

        release_programs(_context)
        _context.release()
        _context = None


def renderer_info() -> dict:
    ctx = create_context()
    return {"renderer": ctx.info.get("GL_RENDERER", "?"),
            "version": ctx.info.get("GL_VERSION", "?"),
            "vendor": ctx.info.get("GL_VENDOR", "?")}
