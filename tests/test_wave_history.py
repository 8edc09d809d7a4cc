"""The wave history as data (issue 41): a frame reads the kept wave state of the grid frame
before it and never changes it, so the same frame twice is the same image, a scrub back
replays nothing, and sub-frames cost one step."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from pxr import Sdf, Usd, UsdGeom

from usdwrinkle.app.frames import frame_paths
from usdwrinkle.cli.main import main
from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.method.history import WaveHistory, cache_capacity, on_grid, reads_index
from usdwrinkle.outputs.images import layout_for

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
EXR = layout_for("x.exr")


def planes(image) -> dict:
    return {name: np.array(plane, copy=True) for name, plane in image.planes.items()}


def assert_identical(a: dict, b: dict, what: str = "") -> None:
    assert a.keys() == b.keys()
    for name in a:
        assert a[name].tobytes() == b[name].tobytes(), f"{what} {name}"


def draw(engine, frame, width=160, height=90) -> dict:
    from usdwrinkle.render.request import FrameRequest

    return planes(engine.render(frame, FrameRequest(width, height, layout=EXR)))


def fresh(ctx, stage, frame, **kwargs) -> dict:
    engine = WrinkleEngine(stage, ctx=ctx, **kwargs)
    try:
        return draw(engine, frame)
    finally:
        engine.release()


def damped_held_shirt(tmp_path) -> str:
    """The shirt with crest damping and held edges on (their state crosses frames)."""
    path = tmp_path / "damped.usda"
    layer = Sdf.Layer.CreateNew(str(path))
    layer.subLayerPaths = [str(SAMPLES / "shirt.usda")]
    layer.Save()
    stage = Usd.Stage.Open(str(path))
    mesh = next(p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
    count = len(UsdGeom.Mesh(mesh).GetPointsAttr().Get(1))
    mesh.CreateAttribute("wrinkle:crestDamping", Sdf.ValueTypeNames.Float).Set(4.0)
    held = np.zeros(count, np.float32)
    held[:20] = 1.0
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "wrinkle:held", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex).Set(held)
    stage.GetRootLayer().Save()
    return str(path)


@pytest.mark.parametrize("frame", [24.0, 17.25])
def test_the_same_frame_drawn_again_is_the_same_image(gl_context, frame):
    engine = WrinkleEngine(str(SAMPLES / "shirt.usda"), ctx=gl_context)
    try:
        first = draw(engine, frame)
        for repeat in range(4):  # drawn 1, 2 and 5 times
            assert_identical(draw(engine, frame), first, f"repeat {repeat + 2}")
        assert_identical(first, fresh(gl_context, str(SAMPLES / "shirt.usda"), frame))
    finally:
        engine.release()


def test_the_same_frame_again_with_crest_damping_and_held_edges(gl_context, tmp_path):
    stage = damped_held_shirt(tmp_path)
    engine = WrinkleEngine(stage, ctx=gl_context)
    try:
        assert engine.meshes[engine.wrinkled_paths[0]].params.crest_damping == 4.0
        for frame in (12.0, 12.5):
            first = draw(engine, frame)
            for _ in range(4):
                assert_identical(draw(engine, frame), first, str(frame))
            assert_identical(first, fresh(gl_context, stage, frame), str(frame))
    finally:
        engine.release()


@pytest.mark.slow
def test_the_same_frame_again_on_cesium_man(gl_context, corpus):
    stage = str(corpus / "usd-wg" / "CesiumMan.usdz")
    engine = WrinkleEngine(stage, ctx=gl_context, all_meshes=True)
    try:
        first = draw(engine, 10.0)
        for _ in range(4):
            assert_identical(draw(engine, 10.0), first)
        sub = draw(engine, 9.5)
        for _ in range(2):
            assert_identical(draw(engine, 9.5), sub)
        assert_identical(first, fresh(gl_context, stage, 10.0, all_meshes=True))
    finally:
        engine.release()


def test_a_step_back_replays_nothing(gl_context):
    stage = str(SAMPLES / "shirt.usda")
    engine = WrinkleEngine(stage, ctx=gl_context)
    try:
        first = draw(engine, 24.0)
        assert engine.debug.computed_count == 24 and engine.debug.preroll_count == 23
        draw(engine, 23.0)
        again = draw(engine, 24.0)
        # 23 reads 22's kept state and 24 reads 23's: two frames, no preroll
        assert engine.debug.computed_count == 26 and engine.debug.preroll_count == 23
        assert_identical(again, first)
        assert_identical(again, fresh(gl_context, stage, 24.0))
    finally:
        engine.release()


def test_a_preroll_leaves_out_the_length_pass_and_draws_the_same(gl_context, monkeypatch):
    """The length pass's scales are read by what is drawn alone (crush sets them to 1 each
    frame; relax and the next frame read the weights beside them), so a preroll step leaves
    the pass out (Step.drawn): frame 12 of the zeppelin drawn after frames 1-11 were drawn,
    each with the pass, is the same image to the bit as frame 12 drawn alone, after a
    preroll of 1-11 without it. By frame 11 the pass scales 182 of its points' folds (down
    to 0.72), so a scale that reached the next frame would show."""
    from usdwrinkle.render.passes.length import LengthPass

    runs: list[bool] = []
    scaled: list[int] = []
    original = LengthPass.run

    def counted(self, res, step):
        runs.append(step.drawn)
        return original(self, res, step)

    monkeypatch.setattr(LengthPass, "run", counted)
    stage = str(SAMPLES / "zeppelin.usda")
    engine = WrinkleEngine(stage, ctx=gl_context)
    try:
        mesh = engine.wrinkled_paths[0]
        for frame in range(1, 12):
            draw(engine, float(frame))
            scaled.append(int((engine.read_fields(mesh).arrays()["length_scale"] < 1).sum()))
        in_order = draw(engine, 12.0)
    finally:
        engine.release()
    assert runs == [True] * 12
    assert scaled[-1] > 100, scaled
    runs.clear()
    alone = fresh(gl_context, stage, 12.0)
    assert runs == [False] * 11 + [True]
    assert_identical(in_order, alone, "frame 12")


def test_a_scrub_past_the_kept_states_replays_from_the_nearest(gl_context):
    stage = str(SAMPLES / "shirt.usda")
    engine = WrinkleEngine(stage, ctx=gl_context, history_cache=3)
    try:
        engine.compute_frame(10.0)
        assert engine.debug.kept_history == [7.0, 8.0, 9.0, 10.0][-3:]
        before = engine.debug.computed_count
        engine.compute_frame(6.0)  # needs 5: nothing kept at or below 5, from the start
        assert engine.debug.computed_count - before == 6
        assert engine.debug.kept_history == [4.0, 5.0, 6.0]
        fields = engine.read_fields(engine.wrinkled_paths[0]).arrays()
    finally:
        engine.release()
    cold = WrinkleEngine(stage, ctx=gl_context)
    try:
        cold.compute_frame(6.0)
        expected = cold.read_fields(cold.wrinkled_paths[0]).arrays()
    finally:
        cold.release()
    assert expected["phase"].tobytes() == fields["phase"].tobytes()


def test_sub_frames_cost_one_step(gl_context, tmp_path):
    stats = tmp_path / "s.json"
    assert main(["render", str(SAMPLES / "shirt.usda"), str(tmp_path / "x.####.exr"),
                 "--frames", "1:24x0.1", "--width", "48", "--height", "27", "--samples", "1",
                 "--write-threads", "0", "--quiet", "--stats", str(stats)]) == 0
    rows = json.loads(stats.read_text())["frames"]
    assert len(rows) == 231
    assert sum(row["preroll_frames"] for row in rows) == 0  # the first frame is the start
    # and each equals the same sub-frame rendered alone (a fresh run: preroll, then it)
    for row in (rows[43], rows[167], rows[229]):
        frame = row["frame"]
        [path] = frame_paths(str(tmp_path / "x.####.exr"), [frame])
        alone = tmp_path / "alone.exr"
        assert main(["render", str(SAMPLES / "shirt.usda"), str(alone), "--frames",
                     repr(frame), "--width", "48", "--height", "27", "--samples", "1",
                     "--quiet"]) == 0
        assert_identical(read_planes(alone), read_planes(path), str(frame))


def read_planes(path) -> dict:
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        return {name: np.array(channel.pixels) for name, channel in f.channels().items()}


def test_the_history_bookkeeping():
    history = WaveHistory(2)
    assert history.slots == 3
    write = history.work_slot()
    history.commit(0, write)
    second = history.work_slot(keep=history.slot(0))
    assert second != write
    history.commit(1, second)
    third = history.work_slot(keep=history.slot(1))
    assert third not in (write, second)
    history.commit(2, third)  # drops 0, the least recently used
    assert history.indices == [1, 2] and history.last == 2
    assert history.nearest_below(5) == 2 and history.nearest_below(0) is None
    assert history.work_slot(keep=history.slot(2)) == write  # 0's slot is free again
    history.clear()
    assert len(history) == 0 and history.last is None
    with pytest.raises(ValueError):
        WaveHistory(0)


def test_which_state_a_frame_reads():
    assert reads_index(1.0, 1.0) is None  # the shot's first frame: cold
    assert reads_index(0.5, 1.0) is None
    assert reads_index(2.0, 1.0) == 0
    assert reads_index(1.25, 1.0) == 0  # a sub-frame reads the grid frame below it
    assert reads_index(5.75, 1.0) == 4
    assert reads_index(None, 1.0) is None  # the default time
    assert on_grid(3.0, 1.0) and not on_grid(3.5, 1.0) and not on_grid(0.0, 1.0)
    assert cache_capacity(1 << 20) == 8 and cache_capacity(1 << 30) == 1
    assert cache_capacity(100 << 20, frames=8, budget=256 << 20) == 2


def test_a_frame_never_changes_the_state_it_reads(gl_context):
    """The state of grid frame 9 (fields, phases, damped directions), read back before and
    after frame 10, 9.5 and 10 again are computed from it: byte for byte the same."""
    engine = WrinkleEngine(str(SAMPLES / "shirt.usda"), ctx=gl_context)
    try:
        engine.compute_frame(9.0)
        path = engine.wrinkled_paths[0]
        index = 9 - 1  # the shirt's history starts at frame 1
        waves = engine.mesh_resources(path).waves
        before = waves.state(engine.history.slot(index)).read()
        for frame in (10.0, 9.5, 10.0):
            engine.compute_frame(frame)
        after = waves.state(engine.history.slot(index)).read()
        for name in ("fields", "phase", "damped"):
            assert before[name].tobytes() == after[name].tobytes(), name
        assert before["damped"][:, 2].min() == 1.0  # crest damping wrote every point
    finally:
        engine.release()
