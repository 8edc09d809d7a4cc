"""Tables (render/resources.Table): element layout across rows, and clear limits."""
from __future__ import annotations

import numpy as np
import pytest

from usdwrinkle.process.errors import UsdWrinkleError
from usdwrinkle.render.bindings import COMMON, TABLE_WIDTH
from usdwrinkle.render.resources import Table


class SmallLimits:
    """The real context, reporting a GL_MAX_TEXTURE_SIZE of 2 rows."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.info = {**ctx.info, "GL_MAX_TEXTURE_SIZE": 2}

    def texture(self, *args, **kwargs):
        return self.ctx.texture(*args, **kwargs)


@pytest.mark.parametrize("count,components,dtype", [(1, 1, "f4"), (TABLE_WIDTH + 7, 4, "f4"),
                                                    (3 * TABLE_WIDTH, 1, "i4"),
                                                    (TABLE_WIDTH - 1, 2, "f4")])
def test_round_trip_and_shader_layout(gl_context, count, components, dtype):
    rng = np.random.default_rng(count)
    numpy_type = np.int32 if dtype == "i4" else np.float32
    data = rng.integers(-1000, 1000, (count, components)).astype(numpy_type)
    table = Table(gl_context, count, components, dtype, data)
    try:
        back = table.read()
        np.testing.assert_array_equal(back.reshape(count, components), data)
        # the shader's fetch(i) must see element i: sum the elements at chosen indices
        sampler = "isampler2D" if dtype == "i4" else "sampler2D"
        kind = "ivec4" if dtype == "i4" else "vec4"
        shader = gl_context.compute_shader(
            "#version 430\n" + "".join(f"#define {k} {v}\n" for k, v in COMMON.items()) +
            "layout(local_size_x = 1) in;\n"
            "#define TABLE_TEXEL(i) ivec2((i) & (TABLE_WIDTH - 1), (i) >> TABLE_WIDTH_LOG2)\n"
            f"layout(binding = 0) uniform {sampler} table;\n"
            "layout(std430, binding = 0) buffer Out { vec4 out_values[]; };\n"
            "uniform int u_index;\n"
            f"void main() {{ {kind} v = texelFetch(table, TABLE_TEXEL(u_index), 0);"
            " out_values[0] = vec4(v); }\n")
        out = gl_context.buffer(reserve=16)
        out.bind_to_storage_buffer(0)
        table.use(0)
        for index in sorted({0, count // 2, count - 1}):
            shader["u_index"] = index
            shader.run(1)
            got = np.frombuffer(out.read(), np.float32)[:components]
            np.testing.assert_array_equal(got, data[index].astype(np.float32))
        out.release()
        shader.release()
    finally:
        table.release()


def test_write_checks_the_size(gl_context):
    table = Table(gl_context, 10, 4)
    try:
        with pytest.raises(ValueError, match="10 x 4"):
            table.write(np.zeros((9, 4), np.float32))
    finally:
        table.release()


def test_too_large_for_the_gpu_is_a_clear_error(gl_context):
    Table(SmallLimits(gl_context), 2 * TABLE_WIDTH, 1).release()  # exactly fits
    with pytest.raises(UsdWrinkleError, match="mesh too large for the GPU"):
        Table(SmallLimits(gl_context), 2 * TABLE_WIDTH + 1, 1, path="/Cloth")
