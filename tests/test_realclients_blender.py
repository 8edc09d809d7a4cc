"""Issue 56: usdwrinkle's Blender add-on (src/usdwrinkle/blender/usdwrinkle_blender.py)
builds the maps layer's MaterialX network out of Blender shader nodes on import, so that
Cycles and EEVEE bend the normals and move the plaid with the folds as usdwrinkle does.
Each test installs and enables the add-on in bpy 5.0.1 as a user does (Install from Disk,
then the checkbox: realclients/addon.py). About 1.5 minutes in all on 2 cores."""
from __future__ import annotations

import json

import numpy as np
import pytest

pytestmark = pytest.mark.realclient

#: the texture shots are seen under the stage's own lights, as in the issue's measure
#: (realclients/cycles_client.py turns the lights Blender's importer leaves in the stage's
#: Y-up axes; bakes.CYCLES_LIGHT_SCALE matches the exposure)
LIGHTING = "stage"


@pytest.fixture(scope="module")
def cycles_texture(realclient, tmp_path_factory):
    """The plaid shirt at frame 24, through the shot's camera and one turned 30 degrees
    that the bake never saw, each zoomed 2x on the upper arm at 480 px (the plaid at its
    960 px size, as the EEVEE check below): Cycles with the add-on, without it, and the
    posed points (32 s alone on 2026-12-03; 71 s for the whole shirt at 960 px)."""
    from realclients.bakes import texture_views

    return texture_views(tmp_path_factory.mktemp("cycles_texture"), turns=(0.0, 30.0),
                         clients=("cycles",), samples=32, lighting=LIGHTING, zoom=2.0)


@pytest.mark.parametrize("degrees", [0.0, 30.0])
def test_cycles_moves_the_texture_with_the_folds_through_the_addon(cycles_texture, degrees):
    """The wrinkle contribution (wrinkled minus plain) over the upper arm, Cycles against
    usdwrinkle. Measured 2026-12-03 (zoomed 2x at 480 px): with the add-on 0.971 at the
    shot's camera and 0.973 at the turned one, its fine part (the plaid's lines, what a
    7x7 box blur leaves) 0.956 and 0.952; without the add-on (the UsdPreviewSurface: the
    first baked frame's normal map, the plaid unmoved) 0.671 and 0.658, fine part 0.318
    and 0.343. Over the whole shirt at 960 px (2026-12-02 and -03): 0.970 and 0.951-0.952,
    fine part 0.958-0.959 and 0.947-0.948; without the add-on 0.700-0.703 and 0.672, fine
    part 0.32-0.33 and 0.34. (Under one uniform dome, where the contribution is the
    texture alone: 0.882 and 0.889.)"""
    network = cycles_texture.contribution(degrees, "cycles_parallax")
    stock = cycles_texture.contribution(degrees, "cycles_stock")
    assert network.correlation() >= 0.92
    assert network.high_pass_correlation() >= 0.9
    assert stock.correlation() <= 0.8
    assert network.high_pass_correlation() - stock.high_pass_correlation() >= 0.4


def test_eevee_moves_the_texture_with_the_folds_through_the_addon(realclient,
                                                                  tmp_path_factory):
    """The same shot in EEVEE at the shot's camera, zoomed 2x on the upper arm at 480 px
    (the plaid at its 960 px size; about 30 s on llvmpipe). Measured 2026-11-29 and again
    2026-12-02: 0.965, fine part 0.911 (under a uniform dome 0.911 and 0.915)."""
    from realclients.bakes import texture_views

    views = texture_views(tmp_path_factory.mktemp("eevee_texture"), turns=(0.0,),
                          clients=("eevee",), lighting=LIGHTING, zoom=2.0)
    network = views.contribution(0.0, "eevee_parallax")
    assert network.correlation() >= 0.92
    assert network.high_pass_correlation() >= 0.85


@pytest.fixture(scope="module")
def shirt_frames(realclient, tmp_path_factory):
    """The shirt (at W = 0.28, realclients/stages/shirt_w028.usda: 512 maps resolve its
    folds) baked with --maps normal,parallax over frames 22-24 and at 22 and at 24 alone,
    through one camera."""
    from realclients.bakes import SHIRT_W028
    from realclients.shots import _usdwrinkle, shared_camera

    folder = tmp_path_factory.mktemp("shirt_frames")
    framed, camera = shared_camera(SHIRT_W028, folder)
    layers = {}
    for name, frames in (("all", "22:24"), ("22", "22"), ("24", "24")):
        layers[name] = folder / f"{name}.usda"
        _usdwrinkle("bake", framed, layers[name], "--frames", frames, "--maps",
                    "normal,parallax", "--map-size", 512, "--quiet")
    return folder, framed, camera, layers


def test_the_addon_plays_the_baked_frames_and_bends_the_normals_as_ours(shirt_frames):
    """The parallax maps of every baked frame become image sequences: the 22-24 layer
    rendered at frame 22 and at 24 gives exactly the images of the layers baked at that
    frame alone (and frame 22 differs from 24). Cycles' Normal pass at frame 24 is
    usdwrinkle's wrinkled normal over the front faces (Cycles' Backfacing AOV; its back
    faces turn a mapped normal its own way: realclients.bakes.cycles_back_face): measured
    median 0.16 degrees, p90 1.9 on 27,183 pixels (0.15 and 1.9 with regular waves; an
    earlier measurement over every pixel within 90 degrees, not repeated since, had 0.04
    and 2.8, and the stock import's normal map 0.04 and 1.6; both off at the cuff, where
    Cycles' reflection clamp tilts steep normals)."""
    from realclients import cycles
    from realclients.bakes import (
        BLENDER_ADDON,
        blender_backfacing,
        blender_normals,
        front_angles,
        our_normals,
    )
    from realclients.shots import _usdwrinkle

    folder, framed, camera, layers = shirt_frames
    jobs = []
    for frame in (22, 24):
        for name in ("all", str(frame)):
            jobs.append({"stage": str(layers[name]), "camera": camera, "frame": frame,
                         "width": 480, "height": 320, "samples": 4,
                         "out": str(folder / f"{name}_at_{frame}.exr"),
                         "addon": str(BLENDER_ADDON), "backfacing": True})
    results = cycles(jobs)
    assert set(results.values()) == {"ok"}, results
    for frame in (22, 24):
        played = blender_normals(folder / f"all_at_{frame}.exr", "Y")[0]
        alone = blender_normals(folder / f"{frame}_at_{frame}.exr", "Y")[0]
        np.testing.assert_array_equal(played, alone)
    back = {frame: blender_backfacing(folder / f"all_at_{frame}.exr") for frame in (22, 24)}
    changed = front_angles(blender_normals(folder / "all_at_22.exr", "Y"),
                           blender_normals(folder / "all_at_24.exr", "Y"), back[22], back[24])
    assert np.percentile(changed[0][changed[1]], 90) > 5.0
    ours = folder / "ours_24.exr"
    _usdwrinkle("render", framed, ours, "--frames", "24", "--width", 480, "--camera", camera,
                "--quiet")
    degrees, mask = front_angles(our_normals(ours),
                                 blender_normals(folder / "all_at_24.exr", "Y"), back[24])
    assert np.median(degrees[mask]) <= 0.2
    assert np.percentile(degrees[mask], 90) <= 4.0


def _imported(layer, folder, addon: bool, name: str) -> dict:
    from realclients import blender_import
    from realclients.bakes import BLENDER_ADDON

    out = folder / f"{name}.json"
    results = blender_import([{"stage": str(layer), "out": str(out),
                               "addon": str(BLENDER_ADDON) if addon else None}])
    assert results[str(out)] == "ok", results
    return json.loads(out.read_text())["Sleeve"]


def test_with_and_without_the_addon_blender_imports_without_error(shirt_frames):
    """Without the add-on, Blender's importer shows the UsdPreviewSurface (the wrinkle
    normal map through a Normal Map node; the first frame's, as it ignores time samples)
    and raises nothing. With it, the parallax maps play as sequences and no Normal Map
    node is left (the network's bent normal feeds the BSDF)."""
    folder, _, _, layers = shirt_frames
    stock = _imported(layers["all"], folder, False, "stock")
    assert stock["normal_images"] == ["Sleeve.normal.0022.png"]
    assert stock["image_sequences"] == []
    network = _imported(layers["all"], folder, True, "network")
    assert network["normal_images"] == []
    assert network["image_sequences"] == [f"Sleeve.parallax{k}.0022.exr" for k in "NST"]
    assert network["materials"] == stock["materials"] == ["Sleeve"]


def test_a_network_the_addon_cannot_build_is_imported_as_its_preview_surface(shirt_frames):
    """A node the add-on has no Blender nodes for (here an id MaterialX does not have):
    the add-on declines the material, and the importer imports its UsdPreviewSurface, as
    without the add-on, with no error."""
    from realclients.shots import over_layer

    folder, _, _, layers = shirt_frames
    broken = folder / "broken.usda"
    stage, _ = over_layer(layers["24"], broken)
    stage.GetPrimAtPath("/World/WrinkleMaterials/Sleeve/MtlxSeen").GetAttribute(
        "info:id").Set("ND_nonesuch_vector3")
    stage.Save()
    imported = _imported(broken, folder, True, "broken")
    assert imported["normal_images"] == ["Sleeve.normal.0024.png"]
    assert imported["image_sequences"] == []


#: the frames of Pixar's skinning stages the Blender import is compared at (1: the rest
#: pose; 10-30: the joints turned, up to 0.05 units apart between the two methods)
SKIN_FRAMES = (1, 10, 15, 20, 30)


def _usdskel_points(baseline, frame):
    """{mesh name: the baseline's world points at ``frame`` in Blender's axes and units}:
    the importer turns a Y-up stage to Z-up ((x, y, z) -> (x, -z, y)) and scales it by
    its metersPerUnit."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(baseline))
    scale = UsdGeom.GetStageMetersPerUnit(stage)
    y_up = UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    found = {}
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh):
            continue
        local = np.asarray(UsdGeom.Mesh(prim).GetPointsAttr().Get(frame), np.float64)
        matrix = np.asarray(UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(frame))
        world = np.c_[local, np.ones(len(local))] @ matrix
        if y_up:
            world = np.stack([world[:, 0], -world[:, 2], world[:, 1]], axis=1)
        found[prim.GetName()] = scale * world[:, :3]
    return found


@pytest.mark.parametrize("name,preserve", [("dqs", True), ("lbs", False)])
def test_blender_skins_usdskel_meshes_as_usdskel_does_with_the_addon(realclient, corpus,
                                                                       tmp_path, name,
                                                                       preserve):
    """Blender's importer skins every UsdSkel mesh by linear blending, whatever its
    ``skel:skinningMethod`` (bpy 5.0.1): Pixar's dual-quaternion test stage bends
    differently in Cycles than in usdview. With the add-on, its meshes get Preserve Volume
    (Blender's dual quaternions), and Blender's posed points are UsdSkel's own baseline
    points (Pixar's ``dqs.baked.usda``, written by UsdSkel's baking) to float precision;
    the linear stage stays linear."""
    from realclients import blender_import
    from realclients.bakes import BLENDER_ADDON

    folder = corpus / "openusd-usdskel"
    imported = {}
    for addon in (False, True):
        out = tmp_path / f"{name}_{addon}.json"
        results = blender_import([{"stage": str(folder / f"{name}.usda"), "out": str(out),
                                   "addon": str(BLENDER_ADDON) if addon else None,
                                   "points_at": list(SKIN_FRAMES)}])
        assert results[str(out)] == "ok", results
        imported[addon] = json.loads(out.read_text())
    skinned = sorted(obj for obj, found in imported[True].items() if found["preserve_volume"])
    assert skinned == ["Mesh", "MeshWithFaceVaryingNormals", "MeshWithNormals"], skinned
    gaps = {True: [], False: []}
    for frame in SKIN_FRAMES:
        expected = _usdskel_points(folder / "baseline" / f"{name}.baked.usda", frame)
        for addon in (False, True):
            for obj in skinned:
                assert imported[addon][obj]["preserve_volume"] == [preserve and addon]
                points = np.asarray(imported[addon][obj]["points"][str(frame)])
                gaps[addon].append(np.abs(points - expected[obj]).max())
    # Blender's metres: the stage's units are centimetres, the arm 3 units (0.03 m) long
    assert max(gaps[True]) < 1e-6, gaps[True]
    if preserve:
        # without the add-on the joints' turns bend it by linear blending: up to 0.05 units
        assert max(gaps[False]) > 3e-4, gaps[False]
    else:
        assert max(gaps[False]) < 1e-6, gaps[False]
