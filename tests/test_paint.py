"""The paint mode's core without Qt (brush/stamp.py, app/paint_session.py): what a stamp does
to q, against numbers worked out by hand, and a session's strokes, undo, controls and save
on the engine (tests/test_paint_window.py drives the window itself)."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from pxr import Usd

from usdwrinkle.app.paint_session import FULL, PaintSession, open_paint_stage
from usdwrinkle.authoring import WrinkleAPI
from usdwrinkle.authoring.builders import grid_sheet
from usdwrinkle.brush.stamp import (
    BrushSettings,
    Hit,
    PaintMesh,
    Stroke,
    clamp_unit,
    falloff,
    flood,
    spread,
    stamp,
)
from usdwrinkle.brush.view import OrbitCamera, pixel_ray, project, ray_triangles
from usdwrinkle.process.errors import UsdWrinkleError

from helpers import sheet_stage


def sheet(nx=21, size=2.0, flip_diagonals=False) -> PaintMesh:
    points, counts, indices = grid_sheet(nx, nx, size)
    quads = np.asarray(indices).reshape(-1, 4)
    if flip_diagonals:  # every quad split along the other diagonal: no mirror symmetry
        tris = np.concatenate([quads[:, [0, 1, 3]], quads[:, [1, 2, 3]]])
    else:
        tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    normals = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    return PaintMesh("/Sheet", points, normals, tris, np.zeros((len(points), 3)),
                     np.full(len(points), 0.2))


def test_falloff_profiles():
    t = np.array([0.0, 0.5, 1.0, 1.5])
    np.testing.assert_allclose(falloff("smooth", t), [1.0, 0.5625, 0.0, 0.0])
    np.testing.assert_allclose(falloff("linear", t), [1.0, 0.5, 0.0, 0.0])
    np.testing.assert_allclose(falloff("constant", t), [1.0, 1.0, 0.0, 0.0])
    np.testing.assert_allclose(falloff("sphere", t), [1.0, np.sqrt(0.75), 0.0, 0.0])
    with pytest.raises(UsdWrinkleError, match="unknown falloff 'spiky'"):
        falloff("spiky", t)


def test_comb_projects_the_stroke_onto_each_tangent_plane():
    mesh = sheet()
    brush = BrushSettings(radius=0.35, strength=1.0, amount=0.8, falloff="constant",
                          geodesic=False)
    touched = stamp(mesh, brush, np.zeros(3), None, np.array([1.0, 1.0, 0.5]))
    inside = np.linalg.norm(mesh.rest_points, axis=1) < 0.35
    assert set(touched.tolist()) == set(np.nonzero(inside)[0].tolist())
    expected = 0.8 * np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)  # the normal's part dropped
    np.testing.assert_allclose(mesh.q[inside], np.tile(expected, (inside.sum(), 1)), atol=1e-6)
    assert not mesh.q[~inside].any()


def _comb_line(mesh, brush, y: float) -> None:
    """Stamps along rest x at height y, spaced as a drag places them (spacing x radius)."""
    for x in np.arange(-0.6, 0.6 + 1e-9, brush.spacing * brush.radius):
        stamp(mesh, brush, np.array([x, y, 0.0]), None, np.array([1.0, 0.0, 0.0]))


def test_a_comb_strokes_folds_die_out_over_a_wavelength_at_its_edges():
    """A stroke painted its full amount up to the brush's rim, so that its folds stood as a
    band cut off along two straight lines (2026-12-06, painting the pull). Across a comb
    stroke on a fine sheet, the fold's height (about sqrt(rho - 1), rho the fold law's
    excess length of the painted q, method.folds.excess_length) falls from 90% to 10% of
    the stroke's own over at least 0.4 W (brush.stamp.COMB_TAPER; measured 0.50 W, 0.125 W
    before), while it stays at 90% out to 0.45 of the radius (measured 0.57: the folds
    span the stroke). A second stroke beside it lowers no q the first painted (no valley
    carved where they overlap)."""
    from usdwrinkle.method.folds import excess_length

    mesh = sheet(nx=101)  # points 0.02 apart: the taper, not the mesh, sets the edge
    w = 0.16
    mesh.width[:] = w
    brush = BrushSettings(radius=0.28, strength=0.5, amount=1.0, geodesic=False)
    _comb_line(mesh, brush, 0.0)
    column = np.abs(mesh.rest_points[:, 0]) < 1e-6  # across the stroke at its middle
    d = np.abs(mesh.rest_points[column, 1])
    size = np.linalg.norm(mesh.q[column], axis=1)
    excess = excess_length(1.0 - size ** 2, 1.0, 0.05) - 1.0
    share = np.sqrt(excess / excess.max())  # the fold height, about sqrt(rho - 1)
    full, none = d[share >= 0.9].max(), d[share > 0.1].max()
    assert none - full >= 0.4 * w, (full, none)
    assert full >= 0.45 * brush.radius, full
    assert none < brush.radius
    before = np.linalg.norm(mesh.q, axis=1)
    _comb_line(mesh, brush, 0.8 * brush.radius)
    assert np.all(np.linalg.norm(mesh.q, axis=1) >= before - 1e-6)


def test_comb_takes_the_sign_of_the_q_already_there():
    mesh = sheet()
    mesh.q[:] = [-0.5, 0.0, 0.0]
    brush = BrushSettings(radius=0.35, strength=0.5, falloff="constant", geodesic=False)
    stamp(mesh, brush, np.zeros(3), None, np.array([1.0, 0.0, 0.0]))
    inside = np.linalg.norm(mesh.rest_points, axis=1) < 0.35
    # a line, not an arrow: towards -x (length 1), not through zero towards +x
    np.testing.assert_allclose(mesh.q[inside, 0], -0.75, atol=1e-6)


def test_q_never_grows_past_one():
    mesh = sheet()
    brush = BrushSettings(radius=0.5, strength=1.0, amount=1.0, geodesic=False)
    for _ in range(20):
        stamp(mesh, brush, np.zeros(3), None, np.array([0.3, 1.0, 0.0]))
    assert np.linalg.norm(mesh.q, axis=1).max() <= 1.0


def test_erase_and_smooth():
    mesh = sheet()
    mesh.q[:] = [0.6, 0.0, 0.0]
    brush = BrushSettings(mode="erase", radius=0.3, strength=1.0, falloff="constant",
                          geodesic=False)
    touched = stamp(mesh, brush, np.zeros(3), None, None)
    assert len(touched) > 5 and not mesh.q[touched].any()
    rng = np.random.default_rng(3)
    noisy = np.array([1.0, 0.0, 0.0]) + 0.8 * rng.normal(size=(mesh.count, 3)) * [1, 1, 0]
    mesh.q[:] = 0.7 * noisy / np.linalg.norm(noisy, axis=1)[:, None]
    before = spread(mesh.q, touched)
    smooth = BrushSettings(mode="smooth", radius=0.3, strength=1.0, geodesic=False)
    for _ in range(3):
        stamp(mesh, smooth, np.zeros(3), None, None)
    assert spread(mesh.q, touched) < 0.75 * before  # measured 0.32 -> 0.22


def test_geodesic_distance_stays_on_the_surface():
    """A strip folded into a U: its arms 0.1 apart in space, 2 apart along the cloth."""
    xs = np.linspace(0.0, 1.0, 11)
    arm_a = np.stack([xs, np.zeros(11), np.zeros(11)], 1)
    arm_b = np.stack([xs[::-1], np.zeros(11), np.full(11, 0.1)], 1)
    points = np.concatenate([arm_a, arm_b, arm_a + [0, 0.1, 0], arm_b + [0, 0.1, 0]])
    n = 22
    strip = []
    for i in range(n - 1):  # quads between row 0 (y = 0) and row 1 (y = 0.1)
        a, b, c, d = i, i + 1, n + i + 1, n + i
        strip += [[a, b, c], [a, c, d]]
    mesh = PaintMesh("/U", points, np.tile([0.0, 0.0, 1.0], (2 * n, 1)), np.array(strip),
                     np.zeros((2 * n, 3)), np.full(2 * n, 0.1))
    straight = mesh.distances(points[0], 0, 0.3, geodesic=False)
    along = mesh.distances(points[0], 0, 0.3, geodesic=True)
    other_arm = np.r_[11:22, 33:44]
    assert np.isfinite(straight[other_arm]).any()  # 0.1 away through the air
    assert not np.isfinite(along[other_arm]).any()  # 2 away along the cloth
    near = np.isfinite(along)
    assert (along[near] >= straight[near] - 1e-12).all()


def test_a_mirrored_stamp_is_exact_on_an_asymmetric_triangulation():
    mesh = sheet(flip_diagonals=True)  # symmetric points, asymmetric edges
    brush = BrushSettings(radius=0.4, strength=0.7, mirror="x")
    stamp(mesh, brush, np.array([0.5, 0.2, 0.0]), None, np.array([1.0, 0.4, 0.0]))
    partner = mesh.mirror_map("x")
    assert (partner >= 0).all()
    mirrored = mesh.q[partner].astype(np.float64) * [-1.0, 1.0, 1.0]
    assert np.abs(mesh.q - mirrored).max() <= 1e-6
    painted = np.linalg.norm(mesh.q, axis=1) > 0.05
    x = mesh.rest_points[:, 0]
    assert painted[x > 0.2].sum() > 5 and painted[x < -0.2].sum() == painted[x > 0.2].sum()


def test_stamps_are_spaced_along_the_drag():
    mesh = sheet()
    brush = BrushSettings(radius=0.2, spacing=0.25, geodesic=False)
    stroke = Stroke(mesh, brush)

    def hit(x):
        return Hit("/Sheet", 0, np.array([1.0, 0, 0]), np.array([x, 0.0, 0.0]), 1.0)

    assert stroke.add(hit(-0.5), None) == 0  # comb waits for a direction
    assert stroke.add(hit(-0.48), None) == 0  # less than a spacing (0.05)
    # 0.5 of travel: a stamp every 0.05, and the press point's now that comb has a direction
    assert stroke.add(hit(0.0), None) == 11
    np.testing.assert_allclose([c[0] for c in stroke.centres], np.arange(11) * 0.05 - 0.5,
                               atol=1e-12)
    assert stroke.add(hit(0.07), None) == 1  # later steps stamp only the new spacings


def test_a_huge_brush_stamps_by_screen_distance_too():
    """Issue 57: at radius 6 a quarter radius (1.5) is farther than a short drag goes, so
    nothing was painted. ``min_step`` (PaintSession: SCREEN_SPACING pixels in rest space)
    caps the spacing: 0.5 of travel with min_step 0.1 stamps at the press and every 0.1."""
    mesh = sheet()
    brush = BrushSettings(radius=6.0, spacing=0.25, geodesic=False)
    stroke = Stroke(mesh, brush)

    def hit(x):
        return Hit("/Sheet", 0, np.array([1.0, 0, 0]), np.array([x, 0.0, 0.0]), 1.0)

    stroke.add(hit(-0.25), None)
    assert stroke.add(hit(0.25), None) == 0  # the brush's own spacing: 1.5
    assert stroke.add(hit(0.25), None, min_step=0.1) == 6
    np.testing.assert_allclose([c[0] for c in stroke.centres], [-0.25, -0.15, -0.05, 0.05,
                                                                0.15, 0.25], atol=1e-12)
    assert np.linalg.norm(mesh.q, axis=1).max() > 0.1


def test_flood_combs_every_vertex():
    mesh = sheet()
    brush = BrushSettings(strength=1.0, amount=0.5)
    flood(mesh, brush, np.array([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(mesh.q, np.tile([0.0, 0.5, 0.0], (mesh.count, 1)), atol=1e-7)


def test_rays_and_projection_agree():
    camera = OrbitCamera(np.zeros(3), 5.0, yaw=30.0, pitch=20.0).record(16 / 9)
    points = np.array([[0.2, 0.1, -0.3], [0.0, 0.0, 0.0]])
    xy, front = project(camera, points, 320, 180)
    assert front.all()
    for point, (x, y) in zip(points, xy, strict=True):
        origin, direction = pixel_ray(camera, x, y, 320, 180)
        closest = origin + direction * ((point - origin) @ direction)
        assert np.linalg.norm(closest - point) < 1e-9
    tri = np.array([[0, 1, 2]])
    corners = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    found = ray_triangles(np.array([0.0, 0.0, 3.0]), np.array([0.0, 0.0, -1.0]), corners, tri)
    assert found[0] == 0 and found[1] == pytest.approx(3.0)
    np.testing.assert_allclose(found[2] @ corners, [0.0, 0.0, 0.0], atol=1e-12)


# -- the session on the engine ------------------------------------------------------
@pytest.fixture
def sheet_session(gl_context, tmp_path):
    stage_path = sheet_stage(tmp_path / "sheet.usda", nx=21)
    out = tmp_path / "painted.usda"
    stage, layer, save = open_paint_stage(stage_path, str(out))
    session = PaintSession(stage, layer, save, ctx=gl_context)
    session.orbit.yaw, session.orbit.pitch = 0.0, 89.0
    session.frame_view(16 / 9)
    yield session, stage_path, out
    session.release()


def sheet_pixel(session, point, width=320, height=180):
    frame = session.last_frame
    posed = np.asarray(point, np.float64)
    xy, _ = project(frame.camera, posed[None], frame.width, frame.height)
    return xy[0, 0] * width / frame.width, xy[0, 1] * height / frame.height


def test_a_session_stroke_is_authored_undone_and_saved(sheet_session):
    session, stage_path, out = sheet_session
    session.render(320, 180, FULL)
    path = session.active
    q0 = session.mesh.q.copy()
    assert session.begin_stroke(*sheet_pixel(session, [-0.5, 0.0, 0.0]), 320, 180)
    for x in np.linspace(-0.45, 0.5, 12):
        session.drag(*sheet_pixel(session, [x, 0.0, 0.0]), 320, 180)
    edit = session.end_stroke()
    assert edit is not None and session.dirty
    q1 = session.mesh.q.copy()
    touched = session.last_touched
    assert len(touched) > 20
    assert (np.abs(q1[touched, 0]) / np.linalg.norm(q1[touched], axis=1)).min() >= 0.99
    # authored through the WrinkleAPI on the paint layer; the engine reads it back
    session.engine.pull_changes()
    np.testing.assert_array_equal(session.engine.meshes[path].params.q, q1)
    session.undo()
    session.engine.pull_changes()
    np.testing.assert_array_equal(session.engine.meshes[path].params.q, q0)
    assert not session.dirty
    session.redo()
    assert session.save() == str(out)
    assert not session.dirty
    saved = Usd.Stage.Open(str(out))
    np.testing.assert_array_equal(WrinkleAPI(saved.GetPrimAtPath(path)).get_q(), q1)
    assert saved.GetRootLayer().subLayerPaths[0] == "./" + os.path.basename(stage_path)
    assert saved.GetStartTimeCode() == 1.0 and saved.GetEndTimeCode() == 2.0


def test_reopening_the_paint_layer_paints_on(sheet_session, gl_context):
    session, stage_path, out = sheet_session
    session.flood()
    session.save()
    stage, layer, save = open_paint_stage(stage_path, str(out))
    assert save == str(out) and layer.realPath == str(out)  # painted further, in place
    again = PaintSession(stage, layer, save, ctx=gl_context)
    try:
        np.testing.assert_array_equal(again.mesh.q, session.mesh.q)
    finally:
        again.release()


def test_live_controls_preview_then_author(sheet_session):
    session, _, _ = sheet_session
    prim = session.stage.GetPrimAtPath(session.active)
    first = session.render(320, 180, FULL).pixels
    assert session.set_control("amplitude_scale", 3.0, live=True) is None
    assert not prim.GetAttribute("wrinkle:amplitudeScale").HasAuthoredValue()
    session.set_control("amplitude_scale", 2.0, live=True)
    edit = session.set_control("amplitude_scale", 2.0)
    assert (edit.before, edit.after) == (1.0, 2.0)
    assert prim.GetAttribute("wrinkle:amplitudeScale").Get() == 2.0
    session.undo()
    assert prim.GetAttribute("wrinkle:amplitudeScale").Get() == 1.0
    np.testing.assert_array_equal(session.render(320, 180, FULL).pixels, first)
    with pytest.raises(UsdWrinkleError, match="slack 2 must be in"):
        session.set_control("slack", 2.0)
    session.set_cloth("denim")
    assert prim.GetAttribute("wrinkle:cloth").Get() == "denim"


def test_the_irregularity_control_previews_authors_and_undoes(sheet_session):
    """wrinkle:irregularity is a live control: dragged, the frame changes and nothing is
    authored; released, it is authored (one undo step); undone, the frame is the first
    again; out of [0, 0.5] it is refused. On the sheet flooded with painted folds."""
    session, _, _ = sheet_session
    prim = session.stage.GetPrimAtPath(session.active)
    session.render(320, 180, FULL)
    session.flood()  # painted folds over the whole sheet
    first = session.render(320, 180, FULL).pixels
    assert session.control("irregularity") == 0.0
    layer = session.stage.GetEditTarget().GetLayer()
    authored = layer.ExportToString()  # the sheet authors irregularity 0 (point_cache_stage)
    session.set_control("irregularity", 0.3, live=True)
    assert prim.GetAttribute("wrinkle:irregularity").Get() == 0.0
    assert layer.ExportToString() == authored
    moved = session.render(320, 180, FULL).pixels
    assert np.abs(moved.astype(np.float64) - first).max() > 0.1 * np.abs(first).max()
    edit = session.set_control("irregularity", 0.3)
    assert (edit.before, edit.after) == (0.0, pytest.approx(0.3))
    assert prim.GetAttribute("wrinkle:irregularity").Get() == pytest.approx(0.3)
    session.undo()
    assert prim.GetAttribute("wrinkle:irregularity").Get() == 0.0
    np.testing.assert_array_equal(session.render(320, 180, FULL).pixels, first)
    with pytest.raises(UsdWrinkleError, match="irregularity 0.8 must be in"):
        session.set_control("irregularity", 0.8)


def test_a_live_preview_keeps_the_history_and_the_edit_restarts_it(sheet_session,
                                                                   gl_context, tmp_path):
    """A stroke previews the current frame from the kept state; once authored, the frame
    is the one a fresh engine renders from the painted stage."""
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.outputs.images import layout_for
    from usdwrinkle.render.request import FrameRequest

    session, _, out = sheet_session
    session.render(320, 180, FULL)
    kept = session.engine.debug.kept_history
    session.flood()  # authored: the history restarts at the next frame
    mesh = session.mesh
    session.engine.preview_params(mesh.path, q=mesh.q * 0.5)
    assert session.engine.debug.kept_history == kept
    session.save()
    session.stage_camera = True
    ours = session.render(320, 180, FULL).pixels
    fresh = WrinkleEngine(str(out), ctx=gl_context)
    try:
        image = fresh.render(session.frame, FrameRequest(320, 180, layout=layout_for("x.png")))
        np.testing.assert_array_equal(ours, image.planes["RGBA"])
    finally:
        fresh.release()


def test_a_session_refuses_what_it_cannot_paint(gl_context, tmp_path):
    stage_path = sheet_stage(tmp_path / "sheet.usda", nx=5)
    stage, layer, save = open_paint_stage(stage_path, None)
    assert save == os.path.realpath(stage_path)  # no -o: the root layer, in place
    with pytest.raises(UsdWrinkleError, match="`prim` /Nope is not a wrinkled mesh"):
        PaintSession(stage, layer, save, prim="/Nope", ctx=gl_context)
    with pytest.raises(UsdWrinkleError, match="cannot open paint layer"):
        bad = tmp_path / "bad.usda"
        bad.write_text("not usd")
        open_paint_stage(stage_path, str(bad))


def test_paint_refuses_in_one_line_before_any_window(tmp_path, capsys, corpus):
    from usdwrinkle.cli.main import main

    lbs = str(corpus / "openusd-usdskel" / "lbs.usda")
    assert main(["paint", lbs, "-o", str(tmp_path / "p.usda")]) == 2
    assert "no mesh has WrinkleAPI applied, so there is nothing to paint" in \
        capsys.readouterr().err
    shirt = str(Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda")
    assert main(["paint", shirt, "--prim", "/World/Nope"]) == 2
    assert "--prim /World/Nope is not a Mesh of the stage" in capsys.readouterr().err
    assert main(["paint", shirt, "--size", "10x10"]) == 2
    assert "--size 10x10 must be between" in capsys.readouterr().err
    assert not (tmp_path / "p.usda").exists()


def test_paint_refuses_an_unusable_display_in_one_line(tmp_path, capsys, monkeypatch):
    """Issue 54, finding 13: DISPLAY set but unreachable died by SIGABRT (Qt's xcb), and
    QT_QPA_PLATFORM=offscreen hung after 'QOpenGLWidget is not supported'."""
    from usdwrinkle.cli.main import main

    stage = sheet_stage(tmp_path / "sheet.usda", nx=5)
    monkeypatch.delenv("QT_QPA_PLATFORM", raising=False)
    monkeypatch.setenv("DISPLAY", ":97")  # no X server there
    assert main(["paint", stage, "-o", str(tmp_path / "p.usda")]) == 2
    err = capsys.readouterr().err
    assert "cannot reach the X display DISPLAY=':97' (no X server answers there)" in err
    for platform in ("offscreen", "minimal"):
        monkeypatch.setenv("QT_QPA_PLATFORM", platform)
        assert main(["paint", stage]) == 2
        assert f"cannot open on Qt's '{platform}' platform" in capsys.readouterr().err
    monkeypatch.delenv("QT_QPA_PLATFORM")
    monkeypatch.delenv("DISPLAY")
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["paint", stage]) == 2
    assert "needs a display (no DISPLAY is set)" in capsys.readouterr().err
    assert not (tmp_path / "p.usda").exists()


def test_paint_refuses_a_missing_camera_an_unwrinkled_prim_and_a_bad_frame(tmp_path, capsys,
                                                                          monkeypatch):
    """Issue 54, finding 16: ``--camera nocam`` opened a black, dead window with a
    traceback; a --prim without WrinkleAPI and a frame that is not a number reached the
    window too. Each is one line before any window (the display is never asked)."""
    from pxr import UsdGeom

    from usdwrinkle.cli.main import main

    monkeypatch.setattr("usdwrinkle.cli.paint.check_display", lambda: pytest.fail("asked"))
    stage_path = sheet_stage(tmp_path / "sheet.usda", nx=5)
    stage = Usd.Stage.Open(stage_path)
    plain = UsdGeom.Mesh.Define(stage, "/Plain")
    plain.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    plain.CreateFaceVertexCountsAttr([3])
    plain.CreateFaceVertexIndicesAttr([0, 1, 2])
    stage.Save()
    assert main(["paint", stage_path, "--camera", "nocam"]) == 2
    assert "camera 'nocam' not found on the stage (cameras: none)" in capsys.readouterr().err
    assert main(["paint", stage_path, "--prim", "/Plain"]) == 2
    assert "--prim /Plain has no WrinkleAPI applied" in capsys.readouterr().err
    assert main(["paint", stage_path, "--frame", "nan"]) == 2
    assert "--frame nan is not a finite time code" in capsys.readouterr().err


def test_session_inputs_are_refused_naming_the_field(sheet_session, gl_context, tmp_path):
    """Issue 54, finding 18: frame=nan raised ValueError, set_control('width', 'abc')
    ValueError, and a brush radius '0.1' TypeError; a frame outside the stage's range is
    said, as render says it."""
    from usdwrinkle.app.paint_session import with_brush
    from usdwrinkle.process import log

    session, stage_path, _ = sheet_session
    with pytest.raises(UsdWrinkleError, match="`frame` nan is not a finite time code"):
        PaintSession(session.stage, session.layer, None, frame=float("nan"), ctx=gl_context)
    with pytest.raises(UsdWrinkleError, match="`frame`='3' must be a number"):
        PaintSession(session.stage, session.layer, None, frame="3", ctx=gl_context)
    with log.collect() as messages:
        PaintSession(session.stage, session.layer, None, frame=999.0,
                     ctx=gl_context).release()
    assert any("lie outside the stage's time range 1..2" in m for m in messages), messages
    with pytest.raises(UsdWrinkleError, match="`width` must be a number, not 'abc'"):
        session.set_control("width", "abc")
    for field, value, message in (("radius", "0.1", "brush `radius` must be a number"),
                                  ("width", 0.0, r"brush `width` 0 must be in \(0"),
                                  ("width", float("nan"), "brush `width` must be finite"),
                                  ("width", 2e15, "brush `width` 2e\\+15 must be in"),
                                  ("strength", True, "brush `strength` must be a number"),
                                  ("mode", "paint", "`mode` 'paint' is not a brush mode")):
        with pytest.raises(UsdWrinkleError, match=message):
            with_brush(session, **{field: value})
    assert session.brush.width == pytest.approx(0.2)  # the brush before stays


def test_an_edit_that_authoring_refuses_leaves_nothing_behind(sheet_session, monkeypatch):
    """Issue 54, finding 3: a width stroke that authoring refused stayed on the mesh: its
    q stayed on the layer, it was not an undo step, dirty stayed False, and every later
    comb stroke raised."""
    from usdwrinkle.authoring import WrinkleAPI

    session, _, _ = sheet_session
    mesh = session.mesh
    q0, w0 = mesh.q.copy(), mesh.width.copy()
    real = WrinkleAPI.CreateWidthPrimvar

    def refuse(self, values):
        raise UsdWrinkleError("width refused (a test's authoring failure)")

    monkeypatch.setattr(WrinkleAPI, "CreateWidthPrimvar", refuse)
    from usdwrinkle.app.paint_session import with_brush

    with_brush(session, mode="width", width=0.05)
    with pytest.raises(UsdWrinkleError, match="width refused"):
        session.flood()
    np.testing.assert_array_equal(mesh.q, q0)
    np.testing.assert_array_equal(mesh.width, w0)
    assert not session.dirty and not session.undo_stack
    assert not session.layer.GetAttributeAtPath("/Sheet.primvars:wrinkle:q")
    monkeypatch.setattr(WrinkleAPI, "CreateWidthPrimvar", real)
    with_brush(session, mode="comb")
    assert session.flood() is not None and session.dirty  # painting goes on


def test_undo_of_a_w_change_right_after_it_is_saved_undone(sheet_session):
    """Issue 54, finding 5: the engine's copy of W is stale until its next frame, so an
    undo right after a change compared with the old W, authored nothing, and the new W
    stayed in the saved layer. The controls read the session's own W (finding 10)."""
    session, _, out = sheet_session
    session.set_control("width", 0.0305)
    assert session.control("width") == pytest.approx(0.0305)
    session.undo()  # no frame drawn in between
    assert session.control("width") == pytest.approx(0.2)
    session.save()
    saved = Usd.Stage.Open(str(out))
    width = WrinkleAPI(saved.GetPrimAtPath("/Sheet")).GetWidthPrimvar().Get()
    assert list(width) == [pytest.approx(0.2)]


def test_esc_during_a_stroke_over_painted_q_shows_what_the_layer_holds(sheet_session):
    """Issue 54, finding 9: a cancelled stroke over painted q stayed on screen while the
    data held only the stroke before it."""
    session, _, _ = sheet_session
    session.render(320, 180, FULL)
    assert session.begin_stroke(*sheet_pixel(session, [-0.5, 0.0, 0.0]), 320, 180)
    for x in np.linspace(-0.45, 0.5, 12):
        session.drag(*sheet_pixel(session, [x, 0.0, 0.0]), 320, 180)
    session.end_stroke()
    first = session.render(320, 180, FULL).pixels
    assert session.begin_stroke(*sheet_pixel(session, [0.0, -0.5, 0.0]), 320, 180)
    for y in np.linspace(-0.45, 0.5, 12):
        session.drag(*sheet_pixel(session, [0.0, y, 0.0]), 320, 180)
    during = session.render(320, 180, FULL).pixels
    assert np.abs(during.astype(int) - first).max() > 16  # the stroke shows while painted
    session.cancel_stroke()
    np.testing.assert_array_equal(session.render(320, 180, FULL).pixels, first)
    assert len(session.undo_stack) == 1


def test_the_mirror_map_matches_all_pairs_and_scales():
    """Issue 54, finding 14: mirror_map compared all pairs (98-113 s for one stroke at
    62,500 points). The grid's answer equals the all-pairs oracle on a jittered mesh, and
    the 62,500-point sheet's partners are its grid's mirror indices (benchmarks/paint.py
    times it)."""
    rng = np.random.default_rng(7)
    mesh = sheet(nx=31)
    half = mesh.rest_points[:, 0] > 1e-9
    jitter = rng.normal(0.0, 6e-4, (half.sum(), 3))
    mesh.rest_points[half] += jitter  # some partners fall outside the tolerance
    tolerance = 1e-2 * mesh.mean_edge()
    mirrored = mesh.rest_points * [-1.0, 1.0, 1.0]
    d2 = ((mirrored[:, None, :] - mesh.rest_points[None, :, :]) ** 2).sum(-1)
    oracle = np.where(d2.min(1) <= tolerance ** 2, d2.argmin(1), -1)
    np.testing.assert_array_equal(mesh.mirror_map("x"), oracle)
    assert 0 < (oracle < 0).sum() < len(oracle)
    big = sheet(nx=250)
    partner = big.mirror_map("x")
    grid = np.arange(250 * 250).reshape(250, 250)
    np.testing.assert_array_equal(partner.reshape(250, 250), grid[:, ::-1])


def symmetric_sheet(nx=21, size=2.0) -> PaintMesh:
    """A sheet whose triangulation is its own mirror image through x = 0 (smooth averages
    over neighbours: only a mirror-symmetric mesh can be smoothed symmetrically)."""
    mesh = sheet(nx, size)
    quads = np.asarray(grid_sheet(nx, nx, size)[2]).reshape(-1, 4)
    left = mesh.rest_points[quads].mean(axis=1)[:, 0] < 0.0
    tris = np.concatenate([quads[left][:, [0, 1, 2]], quads[left][:, [0, 2, 3]],
                           quads[~left][:, [0, 1, 3]], quads[~left][:, [1, 2, 3]]])
    out = PaintMesh("/Sheet", mesh.rest_points, mesh.rest_normals, tris, mesh.q, mesh.width)
    partner = out.mirror_map("x")
    edges = {tuple(sorted(e)) for t in tris for e in ((t[0], t[1]), (t[1], t[2]),
                                                      (t[2], t[0]))}
    assert {tuple(sorted((partner[a], partner[b]))) for a, b in edges} == edges
    return out


@pytest.mark.parametrize("mode", ["comb", "smooth", "erase", "width", "attract"])
def test_a_mirrored_stroke_across_the_plane_is_exactly_symmetric(mode):
    """Issue 54: where a stamp and its mirror overlap (a stroke across the plane), the
    second one acted on the first one's result: an error of 0.28. Both now act at once."""
    mesh = symmetric_sheet() if mode == "smooth" else sheet(flip_diagonals=True)
    rng = np.random.default_rng(3)
    start = rng.normal(0.0, 0.3, (mesh.count, 3)) * [1.0, 1.0, 0.0]
    partner = mesh.mirror_map("x")
    start = 0.5 * (start + start[partner] * [-1.0, 1.0, 1.0])  # a symmetric start
    mesh.q[:] = clamp_unit(start) if mode != "comb" else 0.0
    brush = BrushSettings(mode=mode, radius=0.45, strength=0.8, mirror="x", width=0.05)
    stroke = Stroke(mesh, brush)
    centroids = mesh.rest_points[mesh.triangles].mean(axis=1)
    for x in np.linspace(-0.6, 0.6, 25):  # across the plane x = 0, stamps overlapping
        point = np.array([x, 0.1 + 0.3 * x, 0.0])
        triangle = int(np.argmin(np.linalg.norm(centroids - point, axis=1)))
        stroke.add(Hit("/Sheet", triangle, np.ones(3) / 3, point, 1.0), None)
    assert len(stroke.centres) > 10
    mirrored = mesh.q[partner].astype(np.float64) * [-1.0, 1.0, 1.0]
    # q is a line: on the plane itself a q along x is its own mirror image
    error = np.minimum(np.abs(mesh.q - mirrored).max(1), np.abs(mesh.q + mirrored).max(1))
    assert error.max() <= 1e-6
    np.testing.assert_array_equal(mesh.width, mesh.width[partner])
    changed = np.linalg.norm(mesh.q - (clamp_unit(start) if mode != "comb" else 0.0),
                             axis=1) > 1e-3
    near = np.abs(mesh.rest_points[:, 0]) < 0.1
    # attract on the plane turns q towards the mean of the stroke and its mirror image,
    # along the plane, where the symmetric start's q already lies: it changes off it
    assert mode == "width" or (changed if mode == "attract" else changed[near]).sum() > 3


@pytest.fixture
def shirt_session(gl_context, tmp_path):
    shirt = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"
    stage, layer, save = open_paint_stage(str(shirt), str(tmp_path / "painted.usda"))
    session = PaintSession(stage, layer, save, ctx=gl_context)
    yield session
    session.release()


def _upper_arm_comb(session, amount: float):
    """A comb stroke along rest x from 0.3 to 1.0 over the front of the shirt's upper arm,
    as an artist drags it (pixels of the posed front vertices), with the default brush at
    ``amount``; returns the vertices it touched and the stroke's ends (pixels of a
    640x360 view)."""
    from usdwrinkle.app.paint_session import with_brush

    with_brush(session, amount=amount)
    session.render(640, 360, FULL)
    path = session.active
    rest = session.mesh.rest_points
    facing = session.facing(path)
    posed = session.engine.posed_points(path)
    frame = session.last_frame

    def pixel(x):
        near = facing & (np.abs(rest[:, 0] - x) < 0.1) & (rest[:, 2] > 0)
        xy, _ = project(frame.camera, posed[near], frame.width, frame.height)
        return xy.mean(axis=0) * [640 / frame.width, 360 / frame.height]

    a, b = pixel(0.3), pixel(1.0)
    assert session.begin_stroke(*a, 640, 360)
    for t in np.linspace(0.0, 1.0, 40)[1:]:
        session.drag(*(a + t * (b - a)), 640, 360)
    session.end_stroke()
    return np.array(session.last_touched), a, b


def _height_aov(session, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """The frame's ``wrinkle.height`` AOV and its coverage (alpha), as `render --aovs`
    writes them, from the window's camera."""
    from usdwrinkle.images.aovs import ImageLayout
    from usdwrinkle.render.request import FrameRequest

    camera = session.camera_record(width, height)
    layout = ImageLayout("exr", aovs=("color", "wrinkle.height"))
    image = session.engine.render(session.frame, FrameRequest(width, height, 1, layout=layout,
                                                              camera=camera))
    image.wait()
    out = (np.array(image.planes["wrinkle.height"], np.float64),
           np.array(image.planes["A"], np.float64))
    image.release()
    return out


def _along(plane: np.ndarray, a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    """``plane`` sampled at n points from pixel a to pixel b (bilinear)."""
    t = np.linspace(0.0, 1.0, n)[:, None]
    x, y = (a + t * (b - a)).T - 0.5
    x0 = np.clip(np.floor(x).astype(int), 0, plane.shape[1] - 2)
    y0 = np.clip(np.floor(y).astype(int), 0, plane.shape[0] - 2)
    fx, fy = np.clip(x - x0, 0, 1), np.clip(y - y0, 0, 1)
    top = plane[y0, x0] * (1 - fx) + plane[y0, x0 + 1] * fx
    bottom = plane[y0 + 1, x0] * (1 - fx) + plane[y0 + 1, x0 + 1] * fx
    return top * (1 - fy) + bottom * fy


def _period(samples: np.ndarray, step: float) -> float:
    """The period of a wave profile, in the units of ``step``: twice the mean distance
    between its zero crossings (of the profile less its mean), which needs at least three
    (a window too short for an FFT to resolve: the stroke holds about two folds)."""
    centred = samples - samples.mean()
    crossings = np.flatnonzero(np.signbit(centred[1:]) != np.signbit(centred[:-1]))
    assert len(crossings) >= 3, "the profile holds less than a period"
    # where between the two samples each crossing lies
    exact = crossings + centred[crossings] / (centred[crossings] - centred[crossings + 1])
    return float(2.0 * np.mean(np.diff(exact)) * step)


def test_a_curtain_seen_from_behind_is_painted_on_the_side_seen(gl_context, tmp_path):
    """The curtain sample opens seen from its back (doubleSided; Storm draws both sides):
    none of its 92 points faces the eye with its normal, and a comb stroke across it with
    front-facing only touched none of them and said nothing (2026-12-06). Front-facing
    now means facing the eye on the side the brush meets: the stroke paints the points
    seen, and only those."""
    from usdwrinkle.brush.view import vertex_normals

    curtain = Path(__file__).resolve().parents[1] / "sample_stages" / "curtain.usda"
    stage, layer, save = open_paint_stage(str(curtain), str(tmp_path / "painted.usda"))
    session = PaintSession(stage, layer, save, ctx=gl_context)
    try:
        session.render(640, 360, FULL)
        path = session.active
        posed = session.engine.posed_points(path)
        normals = vertex_normals(posed, session.engine.meshes[path].topology.triangles)
        towards_eye = session.last_frame.camera.position - posed
        seen_front = np.einsum("ij,ij->i", normals, towards_eye) > 0.0
        assert not seen_front.any()  # the case: only its back is seen
        rest = session.mesh.rest_points
        frame = session.last_frame
        middle = np.abs(rest[:, 1] - np.median(rest[:, 1])) < 0.4  # the two middle rows
        xy, _ = project(frame.camera, posed[middle], frame.width, frame.height)
        xy *= [640 / frame.width, 360 / frame.height]
        left, right = xy[np.argmin(xy[:, 0])], xy[np.argmax(xy[:, 0])]
        a, b = left + 0.05 * (right - left), right - 0.05 * (right - left)  # on the cloth
        q0 = session.mesh.q.copy()
        assert session.begin_stroke(*a, 640, 360)
        for t in np.linspace(0.0, 1.0, 30)[1:]:
            session.drag(*(a + t * (b - a)), 640, 360)
        session.end_stroke()
        touched = np.array(session.last_touched)
        changed = np.linalg.norm(session.mesh.q - q0, axis=1) > 1e-3
        assert len(touched) >= 20 and changed.sum() >= 20, (len(touched), changed.sum())
        assert not seen_front[touched].any()
        assert session.facing(path).all() and not session.facing(path, 1.0).any()
        assert session.untouched() is None
        # a brush narrower than the rows' spacing, dragged between two rows, touches no
        # point: the status bar says why instead of nothing happening
        from usdwrinkle.app.paint_session import with_brush

        rows = np.unique(np.round(rest[middle, 1], 6))
        ends = []
        for pick in (np.argmin, np.argmax):  # each row's end, then their mean: between
            row_ends = []
            for y in rows:
                on_row = middle & (np.abs(rest[:, 1] - y) < 1e-6)
                row_xy, _ = project(frame.camera, posed[on_row], frame.width, frame.height)
                row_ends.append(row_xy[pick(row_xy[:, 0])])
            ends.append(np.mean(row_ends, axis=0) * [640 / frame.width, 360 / frame.height])
        a, b = ends[0] + 0.05 * (ends[1] - ends[0]), ends[1] - 0.05 * (ends[1] - ends[0])
        with_brush(session, radius=0.05)
        assert session.begin_stroke(*a, 640, 360)
        for t in np.linspace(0.0, 1.0, 30)[1:]:
            session.drag(*(a + t * (b - a)), 640, 360)
        assert session.end_stroke() is None
        why = session.untouched()
        assert why is not None and path in why and "radius 0.05" in why, why
    finally:
        session.release()


def test_painting_more_gives_deeper_folds_across_the_stroke(shirt_session):
    """Issue 55: a comb stroke gave a narrow band of short, blobby crests, and painting
    more made them finer and darker. Amount 0.5, then 1.0 (each from the unpainted
    shirt), measured on what the stroke adds to the ``wrinkle.height`` AOV as render
    writes it: along the stroke's first 80% (the rest reaches the elbow's own folds), the
    second's folds are deeper (RMS height) and not finer (the dominant period along the
    stroke); lines parallel to the stroke, across its width on screen, fold on at least
    80% of it (both amounts)."""
    session = shirt_session
    size = (1280, 720)
    base, _ = _height_aov(session, *size)  # the unpainted shirt's own folds
    results = {}
    for amount in (0.5, 1.0):
        while session.undo_stack:  # from the unpainted shirt
            session.undo()
        touched, a, b = _upper_arm_comb(session, amount)
        a, b = a * size[0] / 640, b * size[0] / 640
        height, alpha = _height_aov(session, *size)
        painted = height - base  # what the stroke added
        length = float(np.linalg.norm(b - a))
        along, normal = (b - a) / length, np.array([-(b - a)[1], (b - a)[0]]) / length
        # the stroke's width on screen: its touched front vertices across the stroke
        xy, _ = project(session.last_frame.camera, session.engine.posed_points(
            session.active)[touched], session.last_frame.width, session.last_frame.height)
        xy = xy * [size[0] / session.last_frame.width, size[1] / session.last_frame.height]
        offsets = (xy - a) @ normal
        lo, hi = np.percentile(offsets, [2, 98])
        middle = (a, a + along * 0.8 * length)
        n = int(3 * length)  # about 4 samples a pixel
        lines = []
        for offset in np.linspace(lo, hi, 21):
            shift = normal * offset
            on = _along(alpha, middle[0] + shift, middle[1] + shift, n) > 0.99
            lines.append(_along(painted, middle[0] + shift, middle[1] + shift, n)[on])
        centre = _along(painted, *middle, n)
        rms = np.array([np.sqrt(np.mean(line ** 2)) if len(line) > n // 2 else 0.0
                        for line in lines])
        results[amount] = {
            "height": float(np.sqrt(np.mean((centre - centre.mean()) ** 2))),
            "period px": _period(centre, 0.8 * length / n),
            "coverage": float(np.mean(rms > 0.2 * rms.max())),
        }
    low, high = results[0.5], results[1.0]
    assert high["height"] > 1.3 * low["height"], results
    assert high["period px"] >= 0.98 * low["period px"], results
    assert low["coverage"] >= 0.8 and high["coverage"] >= 0.8, results


def test_the_display_ramps_read_the_painted_values():
    """View > Display (issue 57): |q| on the ramp, grey where nothing is painted; W
    against the reference on a log2 ramp, green at the reference."""
    from usdwrinkle.app.paint_session import RAMP, UNPAINTED, display_colors

    mesh = sheet()
    mesh.q[:] = 0.0
    mesh.q[:3] = [[1.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.0005]]
    colors = display_colors(mesh, "amount", 0.1)
    np.testing.assert_allclose(colors[0], RAMP[-1])  # |q| = 1: red
    np.testing.assert_allclose(colors[1], RAMP[2])   # 0.5: green
    np.testing.assert_allclose(colors[2:], np.tile(UNPAINTED, (len(mesh.q) - 2, 1)))
    mesh.width[:] = 0.1
    mesh.width[:2] = [0.4, 0.025]
    colors = display_colors(mesh, "width", 0.1)
    np.testing.assert_allclose(colors[:3], [RAMP[-1], RAMP[0], RAMP[2]], atol=1e-6)
    with pytest.raises(UsdWrinkleError):
        display_colors(mesh, "plaid", 0.1)


def test_attract_turns_q_towards_the_stroke_and_keeps_its_amount():
    """Comb's attract (issue 57): q turns towards the stroke's direction by the stamp's
    weight, its amount kept; where nothing is painted it stays nothing."""
    mesh = sheet()
    painted = np.abs(mesh.rest_points[:, 0]) < 0.5
    mesh.q[painted] = [0.6, 0.0, 0.0]
    before = np.linalg.norm(mesh.q, axis=1)
    brush = BrushSettings(mode="attract", radius=0.4, strength=1.0, falloff="constant",
                          geodesic=False)
    stamp(mesh, brush, np.array([0.0, 0.0, 0.0]), None, np.array([0.0, 1.0, 0.0]))
    after = np.linalg.norm(mesh.q, axis=1)
    np.testing.assert_allclose(after, before, atol=1e-6)
    centre = np.argmin(np.linalg.norm(mesh.rest_points, axis=1))
    np.testing.assert_allclose(np.abs(mesh.q[centre]), [0.0, 0.6, 0.0], atol=1e-6)
    outside = np.linalg.norm(mesh.rest_points, axis=1) > 0.45
    np.testing.assert_allclose(mesh.q[outside & painted], [[0.6, 0.0, 0.0]] * int(
        np.sum(outside & painted)), atol=1e-7)
    assert not mesh.q[~painted].any()
    # half the weight: half way round (45 degrees), the amount kept
    mesh.q[painted] = [0.6, 0.0, 0.0]
    stamp(mesh, BrushSettings(mode="attract", radius=0.4, strength=0.5, falloff="constant",
                              geodesic=False), np.zeros(3), None, np.array([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(np.abs(mesh.q[centre]), [0.6 / np.sqrt(2)] * 2 + [0.0],
                               atol=1e-6)


def test_the_relief_view_draws_as_render_relief(sheet_session, gl_context):
    """View > Relief draws the window's frame as ``usdwrinkle render --relief`` does (the
    same codes through the stage's camera as a fresh engine's frame asked for the relief),
    and differs from the frame without it where the painted folds stand."""
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.outputs.images import layout_for
    from usdwrinkle.render.request import FrameRequest

    session, _, out = sheet_session
    session.flood()
    session.save()
    session.stage_camera = True
    plain = session.render(320, 180, FULL).pixels
    session.set_relief(True)
    ours = session.render(320, 180, FULL).pixels
    fresh = WrinkleEngine(str(out), ctx=gl_context)
    try:
        image = fresh.render(session.frame, FrameRequest(320, 180, relief=True,
                                                         layout=layout_for("x.png")))
        np.testing.assert_array_equal(ours, image.planes["RGBA"])
    finally:
        fresh.release()
    # measured 2026-12-06: 1,890 of the 57,600 pixels change
    assert np.count_nonzero(np.any(ours != plain, axis=-1)) > 500
