"""What the rasteriser costs by itself, before usdwrinkle does anything. The floor
shaders (benchmarks/shaders/) include the real include/common.glsl, so they address
tables exactly as the passes do."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

#: the floor shaders; they #include the package's include/common.glsl
SHADERS = Path(__file__).resolve().parent / "shaders"


def floors(ctx, copy_points: int = 1_000_000) -> dict:
    """What the rasteriser costs before usdwrinkle does anything: an empty dispatch, a
    6-neighbour gather over 50,000 vertices (the memory pattern of crush and relax) through
    storage buffers and through tables (texelFetch, what the passes use), copying 1 M
    points through a table (the least any skin pass does per point), and reading back one
    330 kpixel float RGBA target that was just drawn."""
    from usdwrinkle.render import bindings
    from usdwrinkle.render.resources import Table
    from usdwrinkle.render.shaders import compute_shader

    n = 50_000
    rng = np.random.default_rng(0)
    # neighbours near each vertex, as in a mesh with a good vertex order
    neighbours = np.clip(np.arange(n)[:, None] + rng.integers(-300, 300, (n, 6)), 0, n - 1)
    values = rng.random((n, 4)).astype(np.float32)
    src = ctx.buffer(values.tobytes())
    dst = ctx.buffer(reserve=n * 16)
    idx = ctx.buffer(neighbours.astype(np.int32).tobytes())
    empty, gather, gather_tables, copy = (
        compute_shader(ctx, f"floor_{name}.glsl", bindings.COMMON, SHADERS)
        for name in ("empty", "gather_buffers", "gather_tables", "copy"))
    a_table = Table(ctx, n, 4, data=values)
    c_table = Table(ctx, 6 * n, 1, "i4", neighbours)
    b_table = Table(ctx, n, 4)
    big = int(copy_points)
    big_src = Table(ctx, big, 4, data=np.zeros((big, 4), np.float32))
    big_dst = Table(ctx, big, 4)
    # a target that was just drawn (a cleared but never drawn one reads back much faster)
    target = ctx.texture((703, 469), 4, dtype="f4")
    fbo = ctx.framebuffer(color_attachments=[target])
    plane = np.empty((469, 703, 4), np.float32)

    def timed(fn, repeat=20):
        fn()
        ctx.finish()
        started = time.perf_counter()
        for _ in range(repeat):
            fn()
        ctx.finish()
        return (time.perf_counter() - started) / repeat * 1e3

    def run_ssbo_gather():
        for buf, binding in ((src, 0), (dst, 1), (idx, 2)):
            buf.bind_to_storage_buffer(binding)
        gather.run((n + 63) // 64)

    def run_table_gather():
        a_table.use(0)
        c_table.use(1)
        b_table.bind_image(0)
        gather_tables.run((n + 63) // 64)

    def run_copy():
        big_src.use(0)
        big_dst.bind_image(0)
        copy.run((big + 63) // 64)

    def draw_and_read():
        fbo.use()
        fbo.clear(0.5, 0.5, 0.5, 1.0)
        ctx.finish()
        target.read_into(plane)

    for shader, count in ((gather, n), (gather_tables, n), (copy, big)):
        shader["n"] = count
    out = {"empty_dispatch_ms": timed(lambda: empty.run(1)),
           "gather6_50k_ms": timed(run_ssbo_gather),
           "gather6_50k_tables_ms": timed(run_table_gather),
           "copy_points": big, "copy_points_ms": timed(run_copy, repeat=5),
           "readback_330k_rgba32f_ms": timed(draw_and_read, repeat=10)}
    out["readback_330k_rgba32f_ms"] -= timed(lambda: (fbo.use(), fbo.clear(0.5, 0.5, 0.5, 1.0),
                                                      ctx.finish()), repeat=10)
    # the shaders are the context's (render/shaders.CompiledPrograms), kept for the next run
    for obj in (src, dst, idx, a_table, c_table, b_table, big_src, big_dst, fbo, target):
        obj.release()
    return out

