"""Mip chains of 8-bit textures, made by a compute pass of our own (shaders/mipmap.glsl)
instead of glGenerateMipmap.

On llvmpipe the first glGenerateMipmap of each texture format in a process compiles
Mesa's blit shaders with LLVM, 150-200 ms a format (an sRGB colour texture, then a linear
normal map, each again), in every process: Mesa's shader cache does not keep them, while
it keeps ours. The pass works the same on every GL, so the levels a render samples are
the same bytes on a GPU and on llvmpipe (glGenerateMipmap leaves the filter and the sRGB
rounding to the driver: llvmpipe's levels differ by one code from the exact filter in
a tenth of the texels).

The base level's codes go into one storage buffer that holds the whole chain; each
level is made from the one above it in one dispatch (the bilinear sample at the texel's
centre that GL's blit takes: a 2x2 average where a size halves exactly; with sRGB, in
linear light); the chain is read back and handed to the texture level by level
(glTexImage2D, glTexImage3D for a texture array). A chain larger than the GL's storage
buffer limit, or a GL without the entry points, gets glGenerateMipmap.

For textures made once (a material's colour, a static normal map): the read-back makes
a chain slower than the GL's own once its shaders are compiled (llvmpipe, 2048²: 80-120 ms
against 25-39), so a normal map that changes every frame (a bake's wrinkle maps) keeps
glGenerateMipmap, as do float textures (render/resources.py).
"""
from __future__ import annotations

import ctypes

import numpy as np

from . import bindings
from .glcalls import GLCalls
from .shaders import compute_shader

GL_TEXTURE_2D = 0x0DE1
GL_TEXTURE_2D_ARRAY = 0x8C1A
GL_RGBA = 0x1908
GL_UNSIGNED_BYTE = 0x1401
GL_RGBA8 = 0x8058
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
        self.shader = compute_shader(ctx, "mipmap.glsl",
                                     {**bindings.COMMON, **bindings.MIPMAP})
        self.limit = int(ctx.info.get(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, 1 << 24))

    @classmethod
    def for_context(cls, ctx) -> MipmapPass:
        made = getattr(ctx, "_usdwrinkle_mipmaps", None)
        if made is None:
            made = cls(ctx)
            ctx._usdwrinkle_mipmaps = made
        return made

    def levels(self, codes: np.ndarray, srgb: bool) -> list[np.ndarray]:
        """The levels below the base of ``codes`` ((layers,) height, width, 4 uint8), each
        (layers, h, w, 4) uint8; None where the chain does not fit one storage buffer."""
        codes = np.ascontiguousarray(codes, np.uint8)
        if codes.ndim == 3:
            codes = codes[None]
        layers, height, width = codes.shape[:3]
        sizes = level_sizes(width, height)
        firsts, word = [], layers * width * height
        for w, h in sizes:
            firsts.append(word)
            word += layers * w * h
        if not sizes:
            return []
        if 4 * word > self.limit:
            return None
        buffer = self.ctx.buffer(reserve=4 * word)
        try:
            buffer.write(codes.tobytes())
            buffer.bind_to_storage_buffer(bindings.MIPMAP["MIPMAP_LEVELS"])
            shader = self.shader
            shader["u_layers"] = layers
            shader["u_srgb"] = int(srgb)
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
            data = np.frombuffer(buffer.read(size=4 * (word - start), offset=4 * start),
                                 np.uint8)
        finally:
            buffer.release()
        out, offset = [], 0
        for w, h in sizes:
            size = layers * w * h * 4
            out.append(data[offset:offset + size].reshape(layers, h, w, 4))
            offset += size
        return out


def build_mipmaps(ctx, texture, codes: np.ndarray, srgb: bool) -> None:
    """Give ``texture`` (moderngl, made from ``codes``: height x width x 4, or layers x
    height x width x 4 for a texture array, uint8; GL_SRGB8_ALPHA8 with ``srgb``, else
    GL_RGBA8) its whole mip chain and trilinear filtering, as texture.build_mipmaps()
    would."""
    import moderngl

    calls = GLCalls.get(ctx)
    levels = MipmapPass.for_context(ctx).levels(codes, srgb) if calls.textures else None
    if levels is None:
        texture.build_mipmaps()
        return
    fns = calls.fns
    array = codes.ndim == 4
    target = GL_TEXTURE_2D_ARRAY if array else GL_TEXTURE_2D
    internal = GL_SRGB8_ALPHA8 if srgb else GL_RGBA8
    fns["glActiveTexture"](GL_TEXTURE0 + ctx.default_texture_unit)
    fns["glBindTexture"](target, texture.glo)
    fns["glPixelStorei"](GL_UNPACK_ALIGNMENT, 1)
    for k, level in enumerate(levels, 1):
        layers, h, w = level.shape[:3]
        pointer = level.ctypes.data_as(ctypes.c_void_p)
        if array:
            fns["glTexImage3D"](target, k, internal, w, h, layers, 0, GL_RGBA,
                                GL_UNSIGNED_BYTE, pointer)
        else:
            fns["glTexImage2D"](target, k, internal, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                                pointer)
    texture.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
