"""Mip chains of textures (8-bit, sRGB or linear, and float), made by a compute pass of
our own (shaders/mipmap.glsl) instead of glGenerateMipmap.

On llvmpipe the first glGenerateMipmap of each texture format in a process compiles
Mesa's blit shaders with LLVM, 150-200 ms a format (an sRGB colour texture, then a linear
normal map, each again), in every process: Mesa's shader cache does not keep them, while
it keeps ours. The pass works the same on every GL, so the levels a render samples are
the same bytes on a GPU and on llvmpipe but for texels within 0.01 of a code's tie, which
float32 pow may round either way (glGenerateMipmap leaves the filter and the sRGB
rounding to the driver: llvmpipe's levels differ by one code from the exact filter in
a tenth of the texels, an NVIDIA H200's from ours by up to two).

The base level's codes go into one storage buffer that holds the whole chain; each
level is made from the one above it in one dispatch (the bilinear sample at the texel's
centre that GL's blit takes: a 2x2 average where a size halves exactly; with sRGB, in
linear light); the chain is read back and handed to the texture level by level
(glTexImage2D, glTexImage3D for a texture array). A chain larger than the GL's storage
buffer limit, or a GL without the entry points, gets glGenerateMipmap.

For textures made once (a material's colour, a static normal map, a dome light's
environment): the read-back makes a chain slower than the GL's own once its shaders are
compiled (llvmpipe, 2048²: 80-120 ms against 25-39), so a normal map that changes every
frame (a bake's wrinkle maps) keeps glGenerateMipmap (render/resources.py).
"""
from __future__ import annotations

import ctypes

import numpy as np

from . import bindings
from .glcalls import GLCalls
from .shaders import Variants, compute_shader

GL_TEXTURE_2D = 0x0DE1
GL_TEXTURE_2D_ARRAY = 0x8C1A
GL_RGBA = 0x1908
GL_UNSIGNED_BYTE = 0x1401
GL_RGBA8 = 0x8058
GL_RGBA32F = 0x8814
GL_FLOAT = 0x1406
GL_SRGB8_ALPHA8 = 0x8C43
GL_TEXTURE0 = 0x84C0
GL_UNPACK_ALIGNMENT = 0x0CF5
GL_MAX_SHADER_STORAGE_BLOCK_SIZE = "GL_MAX_SHADER_STORAGE_BLOCK_SIZE"


def level_sizes(width: int, height: int) -> list[tuple[int, int]]:
    """(width, height) of each level below the base, down to 1x1 (GL's sizes)."""
    sizes = []
    while width > 1 or height > 1:
        width, height = max(width // 2, 1), max(height // 2, 1)
        sizes.append((width, height))
    return sizes


class MipmapPass:
    """The compiled pass of one context (``for_context``: made on first use, kept on the
    context object, so that it goes with it)."""

    def __init__(self, ctx):
        self.ctx = ctx
        defines = {**bindings.COMMON, **bindings.MIPMAP}
        #: FLOAT: RGBA32F texels, else RGBA8 words (each compiled on first use)
        self.shaders = Variants(lambda extra: compute_shader(ctx, "mipmap.glsl",
                                                             {**defines, **extra}))
        self.limit = int(ctx.info.get(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, 1 << 24))

    @classmethod
    def for_context(cls, ctx) -> MipmapPass:
        made = getattr(ctx, "_usdwrinkle_mipmaps", None)
        if made is None:
            made = cls(ctx)
            ctx._usdwrinkle_mipmaps = made
        return made

    def levels(self, pixels: np.ndarray, srgb: bool) -> list[np.ndarray] | None:
        """The levels below the base of ``pixels`` ((layers,) height, width, 4: uint8
        codes, or float32), each (layers, h, w, 4) of the same type; None where the chain
        does not fit one storage buffer. ``srgb``: 8-bit codes in sRGB."""
        floats = pixels.dtype != np.uint8
        pixels = np.ascontiguousarray(pixels, np.float32 if floats else np.uint8)
        if pixels.ndim == 3:
            pixels = pixels[None]
        layers, height, width = pixels.shape[:3]
        sizes = level_sizes(width, height)
        firsts, texels = [], layers * width * height
        for w, h in sizes:
            firsts.append(texels)
            texels += layers * w * h
        if not sizes:
            return []
        bytes_per_texel = 16 if floats else 4
        if bytes_per_texel * texels > self.limit:
            return None
        buffer = self.ctx.buffer(reserve=bytes_per_texel * texels)
        try:
            buffer.write(pixels.tobytes())
            buffer.bind_to_storage_buffer(bindings.MIPMAP["MIPMAP_LEVELS"])
            shader = self.shaders(FLOAT=floats)
            shader["u_layers"] = layers
            shader["u_srgb"] = int(srgb and not floats)
            source, source_first = (width, height), 0
            for (w, h), first in zip(sizes, firsts, strict=True):
                shader["u_source_size"] = source
                shader["u_size"] = (w, h)
                shader["u_source_first"] = source_first
                shader["u_first"] = first
                count = layers * w * h
                shader.run((count + bindings.LOCAL_SIZE - 1) // bindings.LOCAL_SIZE)
                self.ctx.memory_barrier()
                source, source_first = (w, h), first
            start = firsts[0]
            data = np.frombuffer(buffer.read(size=bytes_per_texel * (texels - start),
                                             offset=bytes_per_texel * start),
                                 np.float32 if floats else np.uint8)
        finally:
            buffer.release()
        out, offset = [], 0
        for w, h in sizes:
            size = layers * w * h * 4  # components
            out.append(data[offset:offset + size].reshape(layers, h, w, 4))
            offset += size
        return out


def build_mipmaps(ctx, texture, pixels: np.ndarray, srgb: bool) -> None:
    """Give ``texture`` (moderngl, made from ``pixels``: height x width x 4, or layers x
    height x width x 4 for a texture array; uint8 codes, GL_SRGB8_ALPHA8 with ``srgb``
    else GL_RGBA8, or float32, GL_RGBA32F) its whole mip chain and trilinear filtering,
    as texture.build_mipmaps() would."""
    import moderngl

    calls = GLCalls.get(ctx)
    levels = MipmapPass.for_context(ctx).levels(pixels, srgb) if calls.textures else None
    if levels is None:
        texture.build_mipmaps()
        return
    fns = calls.fns
    array = pixels.ndim == 4
    floats = pixels.dtype != np.uint8
    target = GL_TEXTURE_2D_ARRAY if array else GL_TEXTURE_2D
    internal = GL_RGBA32F if floats else (GL_SRGB8_ALPHA8 if srgb else GL_RGBA8)
    kind = GL_FLOAT if floats else GL_UNSIGNED_BYTE
    fns["glActiveTexture"](GL_TEXTURE0 + ctx.default_texture_unit)
    fns["glBindTexture"](target, texture.glo)
    fns["glPixelStorei"](GL_UNPACK_ALIGNMENT, 1)
    for k, level in enumerate(levels, 1):
        layers, h, w = level.shape[:3]
        pointer = level.ctypes.data_as(ctypes.c_void_p)
        if array:
            fns["glTexImage3D"](target, k, internal, w, h, layers, 0, GL_RGBA, kind, pointer)
        else:
            fns["glTexImage2D"](target, k, internal, w, h, 0, GL_RGBA, kind, pointer)
    texture.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
