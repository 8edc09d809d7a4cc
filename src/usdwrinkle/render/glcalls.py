"""GL calls that moderngl does not wrap: fences (glFenceSync, glClientWaitSync),
persistently mapped readback buffers (glBufferStorage, glMapBufferRange), and a texture's
mip levels given one by one (glTexImage2D and glTexImage3D at a level: render/mipmaps.py).

The pipelined readback (render/resolve.py) resolves frame f into one of K readback
buffers, puts a fence behind it, and waits for that fence only after frame f + 1's work
is queued, so that the GPU computes f + 1 while the CPU copies f out. The buffers live in
the client's memory (GL_CLIENT_STORAGE_BIT) and stay mapped, so the copy out is a plain
memcpy: a buffer in the GPU's own memory, mapped for reading, was read at about 2.7 GB/s
on an H200 (moderngl's Buffer.read_into).

The entry points come from the current context's loader: EGL's eglGetProcAddress
(usdwrinkle's own contexts are EGL), else the process's libOpenGL or libGL (glvnd
dispatches them to the current context, also a GLX one). Where they are missing,
``GLCalls.get(ctx).fences`` / ``.mapped`` are false and the readback uses moderngl's
buffers, read synchronously.
"""
from __future__ import annotations

import ctypes
import ctypes.util

import numpy as np

GL_SYNC_GPU_COMMANDS_COMPLETE = 0x9117
GL_SYNC_FLUSH_COMMANDS_BIT = 0x00000001
GL_ALREADY_SIGNALED = 0x911A
GL_TIMEOUT_EXPIRED = 0x911B
GL_CONDITION_SATISFIED = 0x911C
GL_COPY_WRITE_BUFFER = 0x8F37
GL_SHADER_STORAGE_BUFFER = 0x90D2
GL_MAP_READ_BIT = 0x0001
GL_MAP_PERSISTENT_BIT = 0x0040
GL_CLIENT_STORAGE_BIT = 0x0200

#: how long one glClientWaitSync may block (ns) before the wait is retried; a fence of a
#: frame's resolve signals within milliseconds, so a retry only shows a stuck driver
_WAIT_NS = 1_000_000_000

_c = ctypes
#: name -> (result type, argument types) of each entry point used
_SIGNATURES = {
    "glFenceSync": (_c.c_void_p, (_c.c_uint, _c.c_uint)),
    "glClientWaitSync": (_c.c_uint, (_c.c_void_p, _c.c_uint, _c.c_uint64)),
    "glDeleteSync": (None, (_c.c_void_p,)),
    "glFlush": (None, ()),
    "glGenBuffers": (None, (_c.c_int, _c.POINTER(_c.c_uint))),
    "glDeleteBuffers": (None, (_c.c_int, _c.POINTER(_c.c_uint))),
    "glBindBuffer": (None, (_c.c_uint, _c.c_uint)),
    "glBindBufferBase": (None, (_c.c_uint, _c.c_uint, _c.c_uint)),
    "glBufferStorage": (None, (_c.c_uint, _c.c_ssize_t, _c.c_void_p, _c.c_uint)),
    "glMapBufferRange": (_c.c_void_p, (_c.c_uint, _c.c_ssize_t, _c.c_ssize_t, _c.c_uint)),
    "glUnmapBuffer": (_c.c_ubyte, (_c.c_uint,)),
    "glGetError": (_c.c_uint, ()),
}
_FENCE_CALLS = ("glFenceSync", "glClientWaitSync", "glDeleteSync", "glFlush")
#: texture levels given by the caller (render/mipmaps.py); not needed by the readback
_TEXTURE_SIGNATURES = {
    "glActiveTexture": (None, (_c.c_uint,)),
    "glBindTexture": (None, (_c.c_uint, _c.c_uint)),
    "glPixelStorei": (None, (_c.c_uint, _c.c_int)),
    "glTexImage2D": (None, (_c.c_uint, _c.c_int, _c.c_int, _c.c_int, _c.c_int, _c.c_int,
                            _c.c_uint, _c.c_uint, _c.c_void_p)),
    "glTexImage3D": (None, (_c.c_uint, _c.c_int, _c.c_int, _c.c_int, _c.c_int, _c.c_int,
                            _c.c_int, _c.c_uint, _c.c_uint, _c.c_void_p)),
}


def _loaders():
    """Functions that turn a GL entry point's name into its address (or 0)."""
    found = []
    for name in ("EGL", "libEGL.so.1"):
        path = ctypes.util.find_library(name) if "." not in name else name
        if not path:
            continue
        try:
            egl = ctypes.CDLL(path)
        except OSError:
            continue
        get = egl.eglGetProcAddress
        get.restype = ctypes.c_void_p
        get.argtypes = [ctypes.c_char_p]
        found.append(lambda symbol, get=get: get(symbol.encode()) or 0)
        break
    for name in ("libOpenGL.so.0", "libGL.so.1"):
        try:
            lib = ctypes.CDLL(name)
        except OSError:
            continue
        found.append(lambda symbol, lib=lib: _exported(lib, symbol))
    return found


def _exported(lib, symbol: str) -> int:
    try:
        return ctypes.cast(getattr(lib, symbol), ctypes.c_void_p).value or 0
    except AttributeError:
        return 0


class GLCalls:
    """The entry points, loaded once per process; ``fences``: fence objects work;
    ``mapped``: persistently mapped buffers work (GL 4.4 or ARB_buffer_storage)."""

    _instance: GLCalls | None = None

    def __init__(self, extensions: set | frozenset = frozenset(), version: int = 0):
        self.fns: dict = {}
        signatures = {**_SIGNATURES, **_TEXTURE_SIGNATURES}
        for load in _loaders():
            addresses = {name: load(name) for name in signatures}
            if all(addresses[name] for name in _FENCE_CALLS):
                for name, address in addresses.items():
                    if address:
                        result, arguments = signatures[name]
                        self.fns[name] = ctypes.CFUNCTYPE(result, *arguments)(address)
                break
        self.fences = all(name in self.fns for name in _FENCE_CALLS)
        self.mapped = self.fences and all(name in self.fns for name in _SIGNATURES) and \
            (version >= 440 or "GL_ARB_buffer_storage" in extensions)
        #: a texture's levels can be given one by one (render/mipmaps.py)
        self.textures = all(name in self.fns for name in _TEXTURE_SIGNATURES)

    @classmethod
    def get(cls, ctx=None) -> GLCalls:
        """The process's table; ``ctx`` (its first caller's moderngl context) says
        whether buffer storage is there."""
        if cls._instance is None:
            extensions = set(ctx.extensions) if ctx is not None else set()
            version = int(ctx.version_code) if ctx is not None else 0
            cls._instance = cls(extensions, version)
        return cls._instance

    # -- fences ----------------------------------------------------------------------------
    def fence(self) -> int | None:
        """A fence behind every command queued so far in the current context, flushed so
        that the GPU starts them; None where fences are unavailable or refused."""
        if not self.fences:
            return None
        handle = self.fns["glFenceSync"](GL_SYNC_GPU_COMMANDS_COMPLETE, 0)
        if not handle:
            return None
        self.fns["glFlush"]()
        return handle

    def wait(self, handle: int) -> bool:
        """Block until the fence signals; False if the driver says the wait failed (the
        caller then reads anyway: moderngl's read synchronises by itself)."""
        while True:
            status = self.fns["glClientWaitSync"](handle, GL_SYNC_FLUSH_COMMANDS_BIT, _WAIT_NS)
            if status in (GL_ALREADY_SIGNALED, GL_CONDITION_SATISFIED):
                return True
            if status != GL_TIMEOUT_EXPIRED:
                return False

    def signalled(self, handle: int) -> bool:
        """Whether the fence has signalled already (a wait of zero)."""
        return self.fns["glClientWaitSync"](handle, 0, 0) in (GL_ALREADY_SIGNALED,
                                                               GL_CONDITION_SATISFIED)

    def delete(self, handle: int | None) -> None:
        if handle:
            self.fns["glDeleteSync"](handle)


class MappedBuffer:
    """A buffer of ``size`` bytes in client memory, mapped for reading for its whole life
    (glBufferStorage with MAP_READ | MAP_PERSISTENT | CLIENT_STORAGE). A shader writes it
    through ``bind_to_storage_buffer``; after glMemoryBarrier(CLIENT_MAPPED_BUFFER_BARRIER)
    and a fence behind that shader, once the fence has signalled, ``read_into`` copies from
    the mapping, from any thread (no GL call). Raises OSError where the driver refuses
    it."""

    def __init__(self, calls: GLCalls, size: int):
        self.calls = calls
        self.size = int(size)
        fns = calls.fns
        name = ctypes.c_uint(0)
        fns["glGetError"]()  # a stale error is not this buffer's
        fns["glGenBuffers"](1, ctypes.byref(name))
        self.glo = name.value
        # not coherent: the resolve ends in glMemoryBarrier(CLIENT_MAPPED_BUFFER) before
        # its fence (docs/decisions.md, "Persistent mapped readback buffers")
        flags = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT
        fns["glBindBuffer"](GL_COPY_WRITE_BUFFER, self.glo)
        try:
            fns["glBufferStorage"](GL_COPY_WRITE_BUFFER, max(self.size, 4), None,
                                   flags | GL_CLIENT_STORAGE_BIT)
            address = fns["glMapBufferRange"](GL_COPY_WRITE_BUFFER, 0, max(self.size, 4), flags)
        finally:
            fns["glBindBuffer"](GL_COPY_WRITE_BUFFER, 0)
        error = fns["glGetError"]()
        if not address or error:
            self._delete()
            raise OSError(f"glBufferStorage/glMapBufferRange failed (GL error 0x{error:x})")
        self.view = np.ctypeslib.as_array((ctypes.c_uint8 * max(self.size, 4)).from_address(
            address))

    def bind_to_storage_buffer(self, binding: int) -> None:
        self.calls.fns["glBindBufferBase"](GL_SHADER_STORAGE_BUFFER, binding, self.glo)

    def read_into(self, array: np.ndarray, size: int) -> None:
        """Copy the first ``size`` bytes into ``array`` (C-contiguous)."""
        np.copyto(array.reshape(-1).view(np.uint8)[:size], self.view[:size])

    def _delete(self) -> None:
        if self.glo:
            name = ctypes.c_uint(self.glo)
            self.calls.fns["glDeleteBuffers"](1, ctypes.byref(name))  # unmaps it too
            self.glo = 0

    def release(self) -> None:
        self.view = None
        self._delete()
