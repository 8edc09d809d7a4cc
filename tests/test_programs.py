"""Programs are compiled once per GL context and freed with it (issue 58): a second
engine, render job or farm chunk in the process compiles no shader again, and releasing
the context frees every program it compiled (render/shaders.py, CompiledPrograms)."""
from __future__ import annotations

from pathlib import Path

import moderngl

from usdwrinkle import api
from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.render.shaders import CompiledPrograms, is_released, release_programs

SHIRT = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"


def test_a_second_engine_compiles_no_shader_again(gl_context):
    compiled = CompiledPrograms.of(gl_context)
    for _ in range(2):
        engine = WrinkleEngine(str(SHIRT), ctx=gl_context)
        try:
            engine.render_frame(24.0, 64, 48)
        finally:
            engine.release()
        if _ == 0:
            after_first = compiled.compiled
    assert after_first > 0
    assert compiled.compiled == after_first
    # the engine's release left the context's programs alive for the next engine
    released = [key[0] + ":" + key[1][-300:] for key, program in compiled.programs.items()
                if is_released(program)]
    assert released == []


def test_a_second_render_job_and_a_second_farm_chunk_compile_nothing(gl_context, tmp_path):
    from usdwrinkle.engine import EngineOptions
    from usdwrinkle.farm.worker import render_chunk
    from usdwrinkle.outputs.images import layout_for
    from usdwrinkle.outputs.writer import WriteOptions
    from usdwrinkle.render.request import FrameRequest

    compiled = CompiledPrograms.of(gl_context)  # the process's context, as a job's
    api.render(SHIRT, tmp_path / "a.#.png", frames=[24], width=64)
    first = compiled.compiled
    api.render(SHIRT, tmp_path / "b.#.png", frames=[24], width=64)
    assert compiled.compiled == first
    request = FrameRequest(64, 48, layout=layout_for("x.png"))
    for job, iterations in enumerate((4, 6)):  # two jobs: the worker makes a new engine
        result = render_chunk(EngineOptions(str(SHIRT), relax_iterations=iterations),
                              request, WriteOptions(),
                              [24.0], [str(tmp_path / f"chunk{job}.0024.png")], [None], False)
        assert result["error"] is None and len(result["written"]) == 1, result
    assert compiled.compiled == first


def test_the_context_frees_every_program_it_compiled(gl_context):
    ctx = moderngl.create_standalone_context(backend="egl", require=430)  # now current
    try:
        engine = WrinkleEngine(str(SHIRT), ctx=ctx)
        engine.render_frame(24.0, 64, 48)
        engine.release()
        programs = list(CompiledPrograms.of(ctx).programs.values())
        assert programs and not any(is_released(program) for program in programs)
        release_programs(ctx)
        assert all(is_released(program) for program in programs)
        assert CompiledPrograms.of(ctx).programs == {}
    finally:
        ctx.release()
        gl_context.__enter__()  # the process's context current again, for the next tests
