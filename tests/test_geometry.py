"""bake --geometry: the displaced fine mesh against the analytic plane wave and the length
derivation, its normals against its own surface, rigid motion, frame independence,
UsdSkel not skinning it twice, proxy/render purposes, and CesiumMan."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Usd, UsdGeom, UsdSkel

from benchmarks.lengths import sheet_lengths
from usdwrinkle.cli.main import main
from usdwrinkle.method.profiles import PRESETS

from conftest import grid_sheet
from helpers import point_cache_stage, rotation_matrix

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
SHIRT = str(SAMPLES / "shirt.usda")
SLEEVE = "/World/Arm/Sleeve"
FINE = "/World/Arm/Sleeve_wrinkled"


def bake(source, layer, *args) -> None:
    assert main(["bake", str(source), str(layer), "--quiet", "--geometry", *args]) == 0
    return Usd.Stage.Open(str(layer))


def fine_points(stage, path, frame):
    return np.asarray(UsdGeom.Mesh(stage.GetPrimAtPath(path)).GetPointsAttr().Get(frame),
                      np.float64)


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_plane_wave_and_length_restoration(gl_context, tmp_path, preset):
    """Uniform compression r along x: along the middle row the fine mesh's height is the
    plane wave (the fold law's amplitude and posed wavelength r L, within 3%), and its arc
    length over whole wavelengths over the rest length is 1 (the law restores the length
    exactly for every profile; the polyline through the samples is a little short, 2%)."""
    row = sheet_lengths(preset, 0.7, str(tmp_path))
    np.testing.assert_allclose(row["amplitude"], row["expected_amplitude"], rtol=0.03)
    np.testing.assert_allclose(row["wavelength"], row["expected_wavelength"], rtol=0.03)
    np.testing.assert_allclose(row["measured"], 1.0, rtol=0.02)


@pytest.mark.parametrize("preset", ["fold", "sharp", "box"])
def test_the_default_levels_sample_each_profile_as_finely_as_it_turns(gl_context, tmp_path,
                                                                     preset):
    """The default levels give a profile that turns faster than the fold (profiles.
    turning_phase) as many times more samples a wavelength (geometry/options.py): baked at
    them, the compressed sheet's middle row keeps the law's length (1) within 1%. At six
    a wavelength for every profile (until 2026-12-07) sharp kept 0.988 and box 0.971; at
    their own counts 0.996 and 0.993; the fold 0.994 either way."""
    row = sheet_lengths(preset, 0.7, str(tmp_path), None)
    assert 0.99 <= row["measured"] <= 1.01, row["measured"]


def test_the_profile_factor_of_profiles_with_no_turn_or_one_within_a_sample():
    """A flat profile asks for no more samples than the fold (1); an authored zigzag at
    the table's Nyquist rate, whose central slope is 0 and whose turning phase is 0, asks
    for the most (PROFILE_SAMPLING_MAX) instead of dividing by zero."""
    from usdwrinkle.geometry.bake import profile_sampling
    from usdwrinkle.geometry.options import PROFILE_SAMPLING_MAX, SAMPLED_ROUNDING
    from usdwrinkle.method.profiles import fold_profile, profile_preset

    assert profile_sampling(np.zeros(256, np.float32)) == 1.0
    assert profile_sampling(np.tile([1.0, -1.0], 128).astype(np.float32)) == \
        PROFILE_SAMPLING_MAX
    # the samples were measured on the fold at K = 0.9; the default fold (K = 0.97) turns
    # 1.79x as fast
    assert profile_sampling(fold_profile(SAMPLED_ROUNDING)) == 1.0
    assert profile_sampling(profile_preset("fold")) == pytest.approx(1.790, abs=1e-3)
    assert profile_sampling(profile_preset("sharp")) == pytest.approx(1.484, abs=1e-3)


@pytest.fixture(scope="module")
def shirt(tmp_path_factory):
    folder = tmp_path_factory.mktemp("geometry")
    return bake(SHIRT, folder / "shirt_geometry.usdc", "--with-points"), folder


def face_normals_at_vertices(points, faces):
    """Area-weighted face normals averaged at the vertices: the surface's own normals."""
    tri = points[faces]
    face = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals = np.zeros_like(points)
    for corner in range(3):
        np.add.at(normals, faces[:, corner], face)
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)


def test_shirt_layer_has_proxy_and_render_meshes(gl_context, shirt):
    stage, _ = shirt
    fine = stage.GetPrimAtPath(FINE)
    coarse = stage.GetPrimAtPath(SLEEVE)
    assert UsdGeom.Imageable(fine).ComputePurpose() == UsdGeom.Tokens.render
    assert UsdGeom.Imageable(coarse).ComputePurpose() == UsdGeom.Tokens.proxy
    assert UsdGeom.Imageable(fine).GetProxyPrimRel().GetTargets() == [coarse.GetPath()]
    mesh = UsdGeom.Mesh(fine)
    assert mesh.GetSubdivisionSchemeAttr().Get() == UsdGeom.Tokens.none
    assert len(mesh.GetPointsAttr().GetTimeSamples()) == 24
    assert len(mesh.GetNormalsAttr().GetTimeSamples()) == 24
    assert mesh.GetNormalsInterpolation() == UsdGeom.Tokens.vertex
    st = UsdGeom.PrimvarsAPI(fine).GetPrimvar("st")
    assert st.GetInterpolation() == UsdGeom.Tokens.faceVarying
    counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get())
    assert np.all(counts == 3) and len(st.Get()) == counts.sum()
    from pxr import UsdShade
    bound, _ = UsdShade.MaterialBindingAPI(fine).ComputeBoundMaterial()
    assert str(bound.GetPath()) == "/World/Looks/Plaid"
    # the two line up: the same local-to-world at every frame, points in the same space
    for frame in (1, 12, 24):
        cache = UsdGeom.XformCache(frame)
        np.testing.assert_allclose(np.asarray(cache.GetLocalToWorldTransform(fine)),
                                   np.asarray(cache.GetLocalToWorldTransform(coarse)))
    # --with-points bakes the posed points and unbinds the skeleton: nothing is skinned
    root = UsdSkel.Root.Find(coarse)
    assert root and not skinned_prims(stage, str(root.GetPath()))


def skinned_prims(stage, root_path):
    """The prims UsdSkel skins under a SkelRoot (its skinning targets)."""
    root = UsdSkel.Root(stage.GetPrimAtPath(root_path))
    cache = UsdSkel.Cache()
    cache.Populate(root, Usd.PrimDefaultPredicate)
    return {str(query.GetPrim().GetPath())
            for binding in cache.ComputeSkelBindings(root, Usd.PrimDefaultPredicate)
            for query in binding.GetSkinningTargets()}


def test_fine_mesh_is_not_skinned_inside_a_skel_root(gl_context, tmp_path):
    """Without --with-points the SkelRoot stays and skins the coarse mesh; the fine mesh
    beside it holds posed points and has no joint influences: UsdSkel leaves it alone."""
    stage = bake(SHIRT, tmp_path / "g.usdc", "--levels", "1", "--frames", "1:3")
    assert skinned_prims(stage, "/World/Arm") == {SLEEVE}


def test_normals_follow_the_displaced_surface(gl_context, tmp_path):
    """On the compressed flat sheet (a flat base: the surface's own normals are the true
    ones) the authored normals against the fine mesh's own (averaged face normals):
    within 5 degrees at 95% of the vertices, where the waves tilt them by up to ~40."""
    rest, counts, indices = grid_sheet(21, 21, 2.0)
    posed = rest * np.array([0.7, 1, 1], np.float32)
    stage = point_cache_stage(rest, {1: posed}, counts, indices, width=0.3)
    source = tmp_path / "sheet.usda"
    stage.GetRootLayer().Export(str(source))
    layer = bake(source, tmp_path / "sheet_g.usdc", "--levels", "4")
    mesh = UsdGeom.Mesh(layer.GetPrimAtPath("/Sheet_wrinkled"))
    faces = np.asarray(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3)
    points = fine_points(layer, "/Sheet_wrinkled", 1)
    normals = np.asarray(mesh.GetNormalsAttr().Get(1), np.float64)
    own = face_normals_at_vertices(points, faces)
    if mesh.GetOrientationAttr().Get() == UsdGeom.Tokens.leftHanded:
        own = -own
    tilt = np.degrees(np.arccos(np.clip(np.abs(normals[:, 2]), -1, 1)))
    assert np.percentile(tilt, 99) > 20  # the waves are there
    angle = np.degrees(np.arccos(np.clip(np.abs(np.sum(normals * own, axis=1)), -1, 1)))
    assert np.percentile(angle, 95) < 5.0, np.percentile(angle, 95)


def test_unwrinkled_cloth_is_shaded_as_smoothly_as_the_coarse_mesh(gl_context, tmp_path):
    """Issue 23: on the shirt's unwrinkled upper arm (frame 1, away from the painted cuff)
    neighbouring fine normals differ by at most 1.5 degrees at p99: the coarse mesh's
    interpolated shading normals, not its facets (which made up to 35)."""
    layer = bake(SHIRT, tmp_path / "g.usdc", "--frames", "1")
    mesh = UsdGeom.Mesh(layer.GetPrimAtPath(FINE))
    points = fine_points(layer, FINE, 1)
    normals = np.asarray(mesh.GetNormalsAttr().Get(1), np.float64)
    faces = np.asarray(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    upper = (points[edges[:, 0], 0] < 2.2) & (points[edges[:, 1], 0] < 2.2)  # x: along the arm
    assert upper.sum() > 10_000
    cos = np.sum(normals[edges[upper, 0]] * normals[edges[upper, 1]], axis=1)
    angle = np.degrees(np.arccos(np.clip(cos, -1, 1)))
    assert np.percentile(angle, 99) <= 1.5, np.percentile(angle, [50, 90, 99])


def test_rigid_motion_moves_the_fine_points_with_it(gl_context, tmp_path):
    rest, counts, indices = grid_sheet(21, 21, 2.0)
    posed = rest * np.array([0.7, 1, 1], np.float32)
    rotation = rotation_matrix([0.2, 0.9, -0.4], 0.8)
    shift = np.array([1.0, -0.5, 2.0])
    layers = {}
    for name, points in (("plain", posed), ("moved", posed @ rotation.T + shift)):
        stage = point_cache_stage(rest, {1: np.asarray(points, np.float32)}, counts, indices,
                                  width=0.3)
        source = tmp_path / f"{name}.usda"
        stage.GetRootLayer().Export(str(source))
        layers[name] = bake(source, tmp_path / f"{name}_g.usdc", "--levels", "2")
    plain = fine_points(layers["plain"], "/Sheet_wrinkled", 1)
    moved = fine_points(layers["moved"], "/Sheet_wrinkled", 1)
    extent = np.ptp(plain, axis=0).max()  # the sheet's size
    assert np.abs(moved - (plain @ rotation.T + shift)).max() <= 1e-5 * extent


def test_frame_independence(gl_context, tmp_path):
    """Frame 24 alone equals frame 24 of 1..24 (the phase history is replayed)."""
    whole = bake(SHIRT, tmp_path / "whole.usdc", "--levels", "2")
    alone = bake(SHIRT, tmp_path / "alone.usdc", "--levels", "2", "--frames", "24")
    a, b = fine_points(whole, FINE, 24), fine_points(alone, FINE, 24)
    assert np.abs(a - b).max() <= 1e-5 * np.abs(a).max()


def test_render_of_the_layer_shows_wrinkles_on_the_silhouette(gl_context, shirt, tmp_path):
    """Drawn with --no-wrinkles, the render purpose (the fine mesh) changes the elbow's
    outline: coverage differs from the coarse mesh's plain render along the silhouette."""
    stage, folder = shirt
    layer = stage.GetRootLayer().realPath
    outs = {}
    for name, source in (("fine", layer), ("coarse", SHIRT)):
        out = tmp_path / f"{name}.exr"
        assert main(["render", str(source), str(out), "--frames", "24", "--width", "320",
                     "--no-wrinkles", "--quiet"]) == 0
        from helpers import read_pixels as read
        outs[name] = read(out)[..., 3]
    changed = np.abs(outs["fine"] - outs["coarse"]) > 0.5
    assert changed.sum() > 50  # pixels in or out of the outline: a bumpy silhouette


@pytest.mark.parametrize("args,fragment", [
    (["--levels", "11"], "--levels must be in 0..10"),
    (["--levels", "10"], "would make"),
])
def test_geometry_limits(gl_context, tmp_path, capsys, args, fragment):
    assert main(["bake", SHIRT, str(tmp_path / "o.usdc"), "--quiet", "--geometry",
                 *args]) == 2
    err = capsys.readouterr().err
    assert fragment in err
    if fragment == "would make":
        assert SLEEVE in err and "--levels" in err


def test_levels_need_geometry(tmp_path, capsys):
    assert main(["bake", SHIRT, str(tmp_path / "o.usdc"), "--levels", "2"]) == 2
    assert "--levels need --geometry" in capsys.readouterr().err


def test_cesium_man_doubles_every_mesh(gl_context, corpus, tmp_path):
    """CesiumMan, --all-meshes --geometry, 48 frames: every mesh is doubled as proxy and
    render, and the render mesh holds a time sample per frame."""
    source = corpus / "usd-wg" / "CesiumMan.usdz"
    stage = bake(source, tmp_path / "cesium.usdc", "--all-meshes")
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    proxies = [p for p in meshes if UsdGeom.Imageable(p).ComputePurpose() == "proxy"]
    renders = [p for p in meshes if UsdGeom.Imageable(p).ComputePurpose() == "render"]
    assert proxies and len(proxies) == len(renders) == len(meshes) // 2
    for prim in renders:
        assert UsdGeom.Imageable(prim).GetProxyPrimRel().GetTargets()[0] in \
            [p.GetPath() for p in proxies]
        assert len(UsdGeom.Mesh(prim).GetPointsAttr().GetTimeSamples()) == 48


def test_default_levels_keep_fine_edges_within_w_over_s(gl_context, shirt):
    """The default levels: every fine edge at most W/S long in the rest pose (S = 6), and
    the survey's stricter count where the posed waves need it (the shirt at W = 0.1: 5
    levels, where the rest pose alone needs 4)."""
    from usdwrinkle.engine import WrinkleEngine

    stage, _ = shirt
    levels = int(stage.GetRootLayer().customLayerData["usdwrinkle"]["geometry"]["levels"]
                 .split("=")[-1])
    engine = WrinkleEngine(SHIRT)
    try:
        record = engine.meshes[SLEEVE]
    finally:
        engine.release()
    rest = record.rest_points[record.topology.triangles]
    longest = np.linalg.norm(rest[:, [1, 2, 0]] - rest, axis=2).max()
    assert longest / 2 ** levels <= record.params.width.min() / 6
    assert levels == 5 and longest / 2 ** 4 <= record.params.width.min() / 6  # (a) alone: 4
    assert longest / 2 ** 3 > record.params.width.min() / 6


def test_rendering_the_layer_gives_the_right_advice(gl_context, tmp_path, capsys):
    """Issue 27: rendering a geometry layer advised --all-meshes, which wrinkles the
    displaced mesh a second time, and frames outside the baked ones rendered silently."""


    shirt = str(Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda")
    layer = tmp_path / "geo.usda"
    assert main(["bake", shirt, str(layer), "--frames", "20:24", "--geometry", "--levels", "1",
                 "--quiet"]) == 0
    capsys.readouterr()
    assert main(["render", str(layer), str(tmp_path / "g.####.png"), "--frames", "18:21",
                 "--width", "48", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "render with --no-wrinkles" in err and "use --all-meshes" not in err, err
    assert "2 frame(s) lie outside the frames the displaced geometry was baked for (20..24)" \
        in err, err
    assert main(["render", str(layer), str(tmp_path / "h.####.png"), "--frames", "20:21",
                 "--width", "48", "--quiet", "--no-wrinkles"]) == 0
    assert capsys.readouterr().err == ""


def test_the_largest_geometry_the_render_can_draw_on_any_gl45_gpu():
    """MAX_FINE_POINTS is what the render of the displaced mesh holds: its topology table
    (render/resources.topology_block, the largest per point) of a subdivided sheet and of a
    subdivided closed box, scaled to MAX_FINE_POINTS points, fits TABLE_WIDTH x 16384
    elements (GL 4.5's minimum GL_MAX_TEXTURE_SIZE); the old 4 M did not."""
    import trimesh

    from usdwrinkle.geometry.subdivide import MAX_FINE_POINTS, subdivide
    from usdwrinkle.render.bindings import TABLE_WIDTH
    from usdwrinkle.render.resources import topology_block
    from usdwrinkle.scene.topology import build_topology

    box = trimesh.creation.box()
    points, counts, indices = grid_sheet(11, 11, 2.0)
    meshes = [(box.vertices, box.faces),
              (points, build_topology(counts, indices, points).triangles)]
    capacity = TABLE_WIDTH * 16384
    for rest, triangles in meshes:
        fine = subdivide(rest, triangles, 3)
        topology = build_topology(np.full(len(fine.faces), 3), fine.faces.ravel(), fine.points)
        block, _ = topology_block(topology)
        per_point = len(block) / len(fine.points)
        assert 12.0 < per_point < 14.5
        assert MAX_FINE_POINTS * per_point <= capacity < 4_000_000 * per_point


def test_the_fine_mesh_repeats_what_the_coarse_mesh_authors(gl_context, tmp_path):
    """The fine mesh takes a free name beside the coarse mesh, its authored doubleSided and
    orientation, its primvars (constant: copied; vertex: interpolated to the fine corners)
    and its transform: the reset of the transform stack, and a moving transform sampled at
    every baked frame. The scene reads these once (scene/overrides.py); the writer is
    handed them and never sees the stage."""
    from pxr import Gf, Sdf, Vt

    rest, counts, indices = grid_sheet(9, 9, 2.0)
    posed = rest * np.array([0.7, 1, 1], np.float32)
    stage = point_cache_stage(rest, {1: posed, 2: posed, 3: posed}, counts, indices,
                              width=0.5)
    UsdGeom.Xform.Define(stage, "/Sheet_wrinkled")  # the usual name is taken
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Sheet"))
    mesh.CreateDoubleSidedAttr(True)
    mesh.CreateOrientationAttr(UsdGeom.Tokens.leftHanded)
    xformable = UsdGeom.Xformable(mesh)
    xformable.SetResetXformStack(True)
    translate = xformable.AddTranslateOp()
    translate.Set(Gf.Vec3d(0, 0, 0), 1)
    translate.Set(Gf.Vec3d(1, 2, 3), 3)
    primvars = UsdGeom.PrimvarsAPI(mesh)
    primvars.CreatePrimvar("tag", Sdf.ValueTypeNames.Float, UsdGeom.Tokens.constant).Set(2.5)
    primvars.CreatePrimvar("heat", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex).Set(
        Vt.FloatArray.FromNumpy(np.ascontiguousarray(rest[:, 0])))
    source = tmp_path / "sheet.usda"
    stage.GetRootLayer().Export(str(source))

    layer = bake(source, tmp_path / "g.usda", "--levels", "1")
    fine = layer.GetPrimAtPath("/Sheet_wrinkled2")
    assert fine.IsA(UsdGeom.Mesh)
    assert UsdGeom.Imageable(fine).GetProxyPrimRel().GetTargets() == [Sdf.Path("/Sheet")]
    fine_mesh = UsdGeom.Mesh(fine)
    assert fine_mesh.GetDoubleSidedAttr().Get() is True
    assert fine_mesh.GetOrientationAttr().Get() == UsdGeom.Tokens.leftHanded
    fine_xformable = UsdGeom.Xformable(fine)
    assert fine_xformable.GetResetXformStack()
    assert fine_xformable.GetXformOpOrderAttr().Get() == Vt.TokenArray(
        ["!resetXformStack!", "xformOp:transform"])
    assert fine_xformable.GetOrderedXformOps()[0].GetAttr().GetTimeSamples() == [1, 2, 3]
    coarse = UsdGeom.Xformable(layer.GetPrimAtPath("/Sheet"))
    for frame in (1, 2, 3):
        np.testing.assert_allclose(
            np.asarray(fine_xformable.GetLocalTransformation(frame)),
            np.asarray(coarse.GetLocalTransformation(frame)))
    assert np.asarray(coarse.GetLocalTransformation(2))[3, :3].tolist() == [0.5, 1, 1.5]
    fine_primvars = UsdGeom.PrimvarsAPI(fine)
    tag = fine_primvars.GetPrimvar("tag")
    assert tag.GetInterpolation() == UsdGeom.Tokens.constant and tag.Get() == 2.5
    heat = fine_primvars.GetPrimvar("heat")
    assert heat.GetInterpolation() == UsdGeom.Tokens.faceVarying
    corners = np.asarray(fine_mesh.GetFaceVertexIndicesAttr().Get())
    points = fine_points(layer, "/Sheet_wrinkled2", 1)
    # heat is the rest x, linear: the fine corners carry it exactly (posed x = 0.7 rest x)
    np.testing.assert_allclose(np.asarray(heat.Get()), points[corners, 0] / 0.7, atol=1e-5)


def _crossing_pairs_one_by_one(points, faces):
    """The oracle for self_intersections: every pair of triangles sharing no vertex, each
    edge of one cut with the other's plane and the cut point tested by its barycentric
    coordinates (trimesh), one pair at a time."""
    from trimesh.triangles import points_to_barycentric

    found = set()
    for i in range(len(faces)):
        for j in range(i + 1, len(faces)):
            if set(faces[i]) & set(faces[j]):
                continue
            hit = False
            for one, other in ((faces[i], faces[j]), (faces[j], faces[i])):
                tri = points[other]
                normal = np.cross(tri[1] - tri[0], tri[2] - tri[0])
                for k in range(3):
                    start, end = points[one[k]], points[one[(k + 1) % 3]]
                    denominator = normal @ (end - start)
                    if abs(denominator) < 1e-12:
                        continue
                    t = normal @ (tri[0] - start) / denominator
                    if not 0 < t < 1:
                        continue
                    bary = points_to_barycentric(tri[None], (start + t * (end - start))[None])
                    hit |= bool(np.all(bary > 0))
            if hit:
                found.add((i, j))
    return found


def test_self_intersections_finds_the_pairs_that_cross():
    """The crossing measure behind issue 55's "displaced geometry does not pass through
    itself" (tests/test_folds.py, benchmarks/physics/area.py), against a pair-by-pair
    oracle on a soup of random triangles that cross often, with shared corners, and with
    several cell sizes (a pair met in many cells counts once)."""
    from usdwrinkle.geometry.measure import self_intersections

    rng = np.random.default_rng(55)
    points = rng.random((150, 3))
    faces = np.array([rng.choice(len(points), 3, replace=False) for _ in range(90)])
    expected = _crossing_pairs_one_by_one(points, faces)
    assert 20 < len(expected) < 0.5 * len(faces) * (len(faces) - 1) / 2
    for cell in (None, 0.05, 0.3, 2.0):
        got = {tuple(pair) for pair in self_intersections(points, faces, cell=cell).tolist()}
        assert got == expected, cell
    # two triangles through each other, then the same two sharing a corner (not counted)
    cross = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0],
                      [0.2, 0.2, -0.5], [0.3, 0.2, 0.5], [0.2, 0.3, 0.5]], np.float64)
    assert self_intersections(cross, np.array([[0, 1, 2], [3, 4, 5]])).tolist() == [[0, 1]]
    assert len(self_intersections(cross, np.array([[0, 1, 2], [0, 4, 5]]))) == 0
