"""The pass interface (issue 58; render/passes/base.py): a wave pass is one file and one
shader. The worked example of docs/architecture.md, tests/passes/motion.py, runs in the
compute chain when registered, writes its own table on each mesh, and changes no frame.
Every pass of the package declares its units in its own class."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from passes.motion import MotionPass

from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.render.passes.base import Pass, WavePass, registered, wave_passes

SHIRT = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"
SLEEVE = "/World/Arm/Sleeve"


def colour(engine, frame):
    return engine.render_frame(frame, 96, 64, samples=1)["color"].pixels.copy()


def test_the_smallest_wave_pass_runs_in_the_chain_and_owns_its_table(gl_context):
    plain = WrinkleEngine(str(SHIRT), ctx=gl_context)
    try:
        expected = colour(plain, 24.0)
    finally:
        plain.release()
    with registered(MotionPass):
        assert [cls.__name__ for cls in wave_passes()] == [
            "SkinPass", "MotionPass", "NormalsPass", "CrushPass", "RelaxPass", "LengthPass"]
        engine = WrinkleEngine(str(SHIRT), ctx=gl_context)
    try:
        drawn = colour(engine, 24.0)
        res = engine.mesh_resources(SLEEVE)
        motion = MotionPass.table(res, "motion").read()
        posed = res.posed_points.read()[:, :3]
        moved = posed - res.record.rest_points.astype(np.float32)
        # the skinned elbow moves: a pass that wrote nothing would read zeros
        assert np.abs(moved).max() > 0.01
        np.testing.assert_allclose(motion[:, :3], moved, atol=1e-6)
        np.testing.assert_allclose(motion[:, 3], np.linalg.norm(moved, axis=1), atol=1e-6)
        np.testing.assert_array_equal(drawn, expected)  # its own table only
    finally:
        engine.release()
    assert res.owned == {}  # released with the mesh's other tables
    assert MotionPass not in wave_passes()  # registered for the block only


def test_every_pass_declares_its_units_and_its_shader():
    from usdwrinkle.geometry.evaluate import GeometryEvaluator
    from usdwrinkle.maps.raster import MapRasterizer
    from usdwrinkle.render.passes.draw import DrawPass
    from usdwrinkle.render.shaders import ShaderSource

    chain = wave_passes()
    assert [cls.__name__ for cls in chain] == ["SkinPass", "NormalsPass", "CrushPass",
                                               "RelaxPass", "LengthPass"]
    for cls in [*chain, DrawPass, MapRasterizer, GeometryEvaluator, MotionPass]:
        assert issubclass(cls, Pass) and cls.UNITS, cls
        text = ShaderSource(cls.SHADER, root=cls.ROOT).body  # its #includes expanded
        unused = [name for name in cls.UNITS if name not in text]
        assert unused == [], (cls, unused)
    assert all(issubclass(cls, WavePass) and cls.TIMING for cls in chain)
