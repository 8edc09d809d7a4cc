"""The real-client tier: usdwrinkle's frames against usdview's Storm, rendered headless
from Blender's bpy wheel (realclients/), and usdwrinkle's bake outputs through Storm and
Cycles (Blender's USD importer). Marker ``realclient``; without a Python that has
bpy these tests are skipped with the reason, and the run's summary says the tier did not
run (``--require-realclients``, which .ci/run passes, makes that an error).

Cost on this 2-core machine: 207 s for 43 tests on 2026-11-27 (75 s for 36 in an earlier
session, 287 s for 40 in one when the machine ran 2.7 times slower throughout). The split,
from that slower session: the plain frames (8 shots x 2 frames) 28 s, the probes 19 s, the
bake outputs in Storm 76 s (3 shots: 3-4 bakes and 3 renders each), the decoded-normal
cases in Storm 20-30 s each (six renders each side; the three 1280-pixel ones the most)
and Cycles 40 s (one shot, two bakes, 16 samples); Blender's import of a look per purpose
about 20 s. The decoded-normal cases live in test_realclients_normals.py, so that a run
on two or more cores (pytest-xdist, --dist loadfile) gives them a worker of their own."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.realclient

#: image width of the plain frames
PLAIN_WIDTH = 480
#: the bar of issue 24, in 8-bit sRGB over the pixels both renderers cover
MIN_CORRELATION = 0.99
MAX_MEAN_ABS = 3.0
#: what cannot match, and why (docs/method.md, "What Storm shows differently"): the
#: floor and ceiling are the measured size of the difference, with a little room
PLAIN_EXCEPTIONS = {
    "CesiumMan": ("Storm 25.08 drops the authored normals of skinned meshes "
                  "(UsdSkelImaging: 'GPU normal skinning is not yet supported') and shades "
                  "this polygonal mesh faceted; usdwrinkle skins them", 0.975, 8.5),
    "shirt": ("texture filtering: Storm runs on llvmpipe here, whose anisotropic filter is "
              "an elliptical average of unbounded eccentricity (blurrier than a GPU's, and "
              "seconds per frame at grazing angles); usdwrinkle filters as GPUs do, 16 "
              "trilinear probes along the footprint", 0.98, 6.5),
}
PROBE_EXCEPTIONS = {
    "sky_metal": ("Storm reflects a GGX-prefiltered environment; usdwrinkle box-filtered "
                  "mips", 0.98, 6.5),
    "translucent": ("Storm sorts translucent fragments (OIT); usdwrinkle sorts meshes",
                    0.985, 3.0),
}


@pytest.fixture(scope="module")
def plain(realclient, tmp_path_factory):
    from realclients.shots import PLAIN_SHOTS, compare_plain_frames

    return compare_plain_frames(PLAIN_SHOTS, tmp_path_factory.mktemp("plain"),
                                width=PLAIN_WIDTH)


def test_plain_frames_match_storm(plain):
    """Issue 24: the sample stages, CesiumMan and two Pixar UsdSkel stages, each at two
    frames, through both renderers with the same camera."""
    failures = []
    for comparison in plain:
        name, match = comparison.shot.name, comparison.match
        floor, ceiling = (PLAIN_EXCEPTIONS[name][1:] if name in PLAIN_EXCEPTIONS
                          else (MIN_CORRELATION, MAX_MEAN_ABS))
        if not (match.correlation >= floor and match.mean_abs <= ceiling
                and match.iou >= 0.98 and match.pixels > 1500):
            failures.append(f"{name} {comparison.frame:g}: {match}")
    assert not failures, failures


def test_the_exceptions_are_what_they_say(realclient, tmp_path):
    """Each plain-frame exception is its stated cause and nothing else: with its textures
    flattened to one grey (filtering drops out) the shirt meets the bar, and so
    does CesiumMan once his primvars:normals are blocked too (Storm's skinned-normals
    limitation drops out: both shade him faceted)."""
    from realclients.shots import (
        CORPUS,
        SAMPLES,
        Shot,
        compare_plain_frames,
        flat_textures,
        over_layer,
    )

    shots = []
    for name, source, all_meshes, width in (
            ("shirt", SAMPLES / "shirt.usda", False, None),
            ("CesiumMan", CORPUS / "usd-wg" / "CesiumMan.usdz", True, 640)):
        stage, layer = over_layer(source, tmp_path / f"{name}_flat.usda")
        assert flat_textures(stage, tmp_path) == 1
        if name == "CesiumMan":
            blocked = 0
            for prim in stage.Traverse():
                if prim.HasAttribute("primvars:normals"):
                    prim.GetAttribute("primvars:normals").Block()
                    blocked += 1
            assert blocked
        layer.Save()
        shots.append(Shot(name, Path(layer.realPath), (24,), all_meshes=all_meshes,
                          width=width))
    for comparison in compare_plain_frames(shots, tmp_path, width=PLAIN_WIDTH):
        assert comparison.match.correlation >= MIN_CORRELATION, (comparison.shot.name,
                                                                 comparison.match)
        assert comparison.match.mean_abs <= MAX_MEAN_ABS, (comparison.shot.name,
                                                           comparison.match)


def test_a_missing_frame_is_an_error_that_names_it(tmp_path):
    """A renderer that wrote no frame: the comparison says which file, instead of
    comparing an empty image (OIIO 3 returns one for a file it cannot open)."""
    from realclients.compare import read_rgba8

    missing = tmp_path / "nothing.png"
    with pytest.raises(OSError, match="nothing.png"):
        read_rgba8(missing)


def test_usdview_defaults_show_the_samples_lit(plain, tmp_path):
    """usdview's defaults add its camera light to a stage's lights: the samples are lit
    (they rendered black before), 1.2-1.4x brighter than usdwrinkle's frames."""
    from realclients import storm
    from realclients.compare import read_rgba8
    from realclients.shots import has_lights, shared_camera

    samples = [c for c in plain if c.frame == 24 and has_lights(c.shot.stage)]
    assert len(samples) == 5
    jobs = []
    for comparison in samples:
        stage, camera = shared_camera(comparison.shot.stage, tmp_path)
        jobs.append({"stage": str(stage), "camera": camera, "frame": 24,
                     "width": PLAIN_WIDTH,
                     "out": str(tmp_path / f"{comparison.shot.name}.png"),
                     "camera_light": True})
    assert set(storm(jobs).values()) == {"ok"}
    for comparison, job in zip(samples, jobs, strict=True):
        ours, theirs = read_rgba8(comparison.ours), read_rgba8(job["out"])
        both = (ours[..., 3] == 255) & (theirs[..., 3] == 255)
        ratio = theirs[both][:, :3].mean() / ours[both][:, :3].mean()
        assert 1.0 <= ratio <= 1.6, (comparison.shot.name, ratio)


@pytest.fixture(scope="module")
def probes(realclient, tmp_path_factory):
    from realclients.probes import PROBES, write_probe
    from realclients.shots import Shot, compare_plain_frames

    folder = tmp_path_factory.mktemp("probes")
    shots = [Shot(name, write_probe(folder, name), (1,)) for name in PROBES]
    return {c.shot.name: c for c in compare_plain_frames(shots, folder / "out", width=320)}


@pytest.mark.parametrize("name", ["rect", "disk_shaped", "sphere_warm", "sun_cool", "clipped",
                                  "glossy", "metal", "sky_diffuse", "sky_metal",
                                  "translucent", "headlight_glossy"])
def test_lights_and_surfaces_match_storm(probes, name):
    match = probes[name].match
    floor, ceiling = (PROBE_EXCEPTIONS[name][1:] if name in PROBE_EXCEPTIONS
                      else (MIN_CORRELATION, MAX_MEAN_ABS))
    assert match.correlation >= floor and match.mean_abs <= ceiling, match


def test_a_dome_without_a_texture_lights_as_usdlux_says_and_storm_ignores_it(probes):
    """UsdLux: a dome without a texture emits its colour from every direction; Storm
    leaves it out. Ours is the brighter by about the dome's diffuse contribution."""
    from realclients.compare import read_rgba8

    comparison = probes["plain_dome"]
    ours, theirs = read_rgba8(comparison.ours), read_rgba8(comparison.storm)
    both = (ours[..., 3] == 255) & (theirs[..., 3] == 255)
    difference = ours[both][:, :3].astype(float) - theirs[both][:, :3].astype(float)
    assert np.mean(difference) > 20  # the dome's light, missing in Storm
    assert np.percentile(difference, 1) >= -1  # and nothing else differs the other way


def test_the_clipping_range_cuts_the_near_sphere(probes):
    from realclients.compare import read_rgba8

    clipped = read_rgba8(probes["clipped"].ours)
    whole = read_rgba8(probes["rect"].ours)
    assert np.count_nonzero(clipped[..., 3]) < 0.9 * np.count_nonzero(whole[..., 3])


def test_probes_are_documented():
    from realclients.probes import PROBES

    assert set(PROBE_EXCEPTIONS) <= set(PROBES)
    method = (Path(__file__).resolve().parents[1] / "docs" / "method.md").read_text()
    for reason, *_ in (*PLAIN_EXCEPTIONS.values(), *PROBE_EXCEPTIONS.values()):
        assert reason.split(" (")[0].split(";")[0][:40] in method, reason


# --- issue 23: the bake outputs as Storm shows them ------------------------------------

#: the bar of issue 23: the wrinkle contribution of Storm's render of the maps layer
#: against usdwrinkle's, in every tile of a 4 x 4 grid where the wrinkles show (the
#: shirt's elbow and cuff, pull's sheet, CesiumMan's body and limbs)
MIN_MAPS_CORRELATION = 0.95
#: the coarse surface's cosine with the eye under which the maps test leaves a pixel out
#: (a view that grazes the cloth; test_maps_show_in_storm_what_usdwrinkle_draws)
GRAZING_COSINE = 0.25
#: CesiumMan's head tile in Contribution.tiles' grid (row, column): the shoulders' folds
#: along its bottom rows
HEAD_TILE = {"CesiumMan": (0, 2)}
#: the geometry layer, Storm (render purpose) against usdwrinkle's render of that layer
MIN_GEOMETRY_CORRELATION = 0.98


@pytest.fixture(scope="module")
def turned_texture_views(realclient, tmp_path_factory):
    """The plaid shirt at frame 24 through a camera turned 30 degrees from the shot's,
    which the bake never saw, zoomed 3x on the upper arm and rendered at 320 px (so the
    plaid has its 960 px size), under one uniform white dome (bakes.uniform_dome: the
    wrinkle contribution then shows the texture, not how each renderer shades). The maps
    are baked at 512 texels: Storm's render of the network costs as the float parallax
    maps grow, on llvmpipe (measured 2026-12-02, one render alone: 36 s at 512, 101 s at
    1024, 256 s at 2048; its unwrinkled baseline 11 s; this fixture alone 58 s at 512,
    138 s at 1024 on 2026-12-03), and the measure below barely moves with it (0.884 and
    0.888 at 512, 0.886 and 0.890 at 1024 and at 2048; the bars are 0.85)."""
    from realclients.bakes import texture_views

    return texture_views(tmp_path_factory.mktemp("texture"), turns=(30.0,), zoom=3.0,
                         lighting="dome", map_size=512)


def test_storm_moves_the_texture_with_the_folds_for_a_camera_the_bake_never_saw(
        turned_texture_views):
    """Issue 56: the maps layer's MaterialX network moves the plaid with the folds in Storm
    as usdwrinkle does, for any camera. Measured 2026-11-29 (against the network without
    the wrinkles, bakes.unwrinkled_network): 0.887, fine part (7x7 high-pass) 0.890 (on
    2026-12-02 0.886 and 0.890, with the maps at 1024 and at 2048 texels alike; at the
    512 this test bakes, 0.884 and 0.888, the UsdPreviewSurface 0.141 on 2026-12-03);
    through the UsdPreviewSurface alone 0.142 and 0.249 (zoomed 2x at 480 px: 0.898 and
    0.905, 0.158 and 0.236). What is left is how Storm draws on llvmpipe, not the network
    (python -m benchmarks.texture_gap, the README's block): read through a ramp texture,
    Storm's texture coordinates are wrong on about a quarter of the pixels, with or without
    wrinkles (its dotted lines along triangle edges with any MaterialX material), and its
    texture filtering is softer than ours; without those pixels and with ours blurred to
    its sharpness, 0.952 here and 0.950 at the shot's own camera."""
    network = turned_texture_views.contribution(30.0, "storm_parallax")
    preview = turned_texture_views.contribution(30.0, "storm_normal")
    assert network.correlation() >= 0.85
    assert network.high_pass_correlation() >= 0.85
    assert preview.correlation() <= 0.3


@pytest.fixture(scope="module")
def bake_views(realclient, tmp_path_factory):
    from realclients.bakes import MAP_SHOTS, bake_views

    folder = tmp_path_factory.mktemp("bakes")
    return {shot.name: bake_views(shot, folder / shot.name, display_color=True)
            for shot in MAP_SHOTS}


@pytest.mark.parametrize("name", ["shirt", "pull", "CesiumMan"])
def test_maps_show_in_storm_what_usdwrinkle_draws(bake_views, name):
    """Issue 23: usdview's Storm shows the maps layer's wrinkles as usdwrinkle draws them,
    everywhere they show (was 0.58 at the shirt's elbow and 0.82 for CesiumMan), but
    where usdwrinkle's draw turns a bent normal back to its horizon (a seen point faces
    the eye; contract.HORIZON_COSINE), which a normal map, the same in every view,
    cannot: those pixels (measured 2026-12-06, grown by a pixel: shirt 2.9%, pull 1.9%,
    CesiumMan 2.7% of the compared ones) are left out, and are few. With them the
    correlations were 0.995, 0.994 and 0.934, the least tiles 0.966, 0.982 and 0.921
    (CesiumMan's hips and thigh); without them 0.996, 0.998 and 0.991, tiles from 0.967.
    The pixels left out are those within two pixels of a turned one (2026-12-07): beside
    a turned pixel the view is grazing, and the two images part there over more than the
    antialiasing's pixel (RMS of their difference at 1 / 2 / 3 pixels from a turned one,
    against the rest: shirt 14.4 / 8.9 / 4.7 codes against 2.3, pull 3.5 / 2.3 / 1.4
    against 0.7, CesiumMan 8.1 / 3.8 / 2.7 against 0.9); with one pixel, CesiumMan's
    head tile, the shoulders' folds along its bottom rows, scored 0.954, and 0.934 with the
    cold start's mean (docs/physics.md, "What that tile is").
    Also left out (2026-12-07): the pixels where the view grazes the coarse surface
    (GRAZING_COSINE), where the map's folds show weaker in Storm than usdwrinkle draws
    them, and part the more, the more the view grazes (CesiumMan, RMS of the difference by the
    coarse cosine: 0.77 codes above 0.5, 1.9 at 0.35-0.5, 2.7 at 0.25-0.35, 5.4 at
    0.15-0.25, 11.3 under 0.15, where ours is 22 codes and Storm's 19). Those are
    0.7% of CesiumMan's compared pixels, 0.9% of the shirt's and none of the pull's;
    17 of them held 57% of the squared difference of CesiumMan's head tile, which scored
    0.937 with them and 0.966 without (docs/physics.md, "The grazing pixels"). That tile
    counts when our contribution's deviation there reaches Contribution.tiles' 3 codes:
    2.98 now, so it must pass when it does."""
    views = bake_views[name]
    contribution = views.maps()
    turned = views.horizon_turned(grow=2) & contribution.mask
    assert turned.sum() <= 0.05 * contribution.mask.sum(), turned.mean()
    grazing = views.grazing(GRAZING_COSINE) & contribution.mask & ~turned
    assert grazing.sum() <= 0.02 * contribution.mask.sum(), grazing.mean()
    contribution.mask &= ~(turned | grazing)
    if name in HEAD_TILE:  # the tile the deviation filter leaves out by 0.02 codes
        head = contribution.tiles(min_std=0.0, min_share=0.0)[HEAD_TILE[name]]
        assert head[0] >= MIN_MAPS_CORRELATION, head
    tiles = contribution.tiles()
    assert len(tiles) >= 8, tiles  # the wrinkles show over most of the mesh
    low = {k: v for k, v in tiles.items() if v[0] < MIN_MAPS_CORRELATION}
    assert not low, (name, low)
    assert contribution.correlation() >= 0.97, name
    # and Storm's wrinkles are as strong as ours (not merely correlated)
    strength = contribution.theirs[contribution.mask].std() / \
        contribution.ours[contribution.mask].std()
    assert 0.85 <= strength <= 1.15, (name, strength)


@pytest.mark.parametrize("name", ["shirt", "pull", "CesiumMan"])
def test_geometry_layer_shows_in_storm_as_in_usdwrinkle(bake_views, name):
    """Storm with the render purpose draws the geometry layer's displaced mesh as
    usdwrinkle draws that layer (issue 23: >= 0.98; measured 0.989-0.997)."""
    from realclients.compare import compare

    views = bake_views[name]
    match = compare(views.images["ours_geometry"], views.images["storm_geometry"])
    assert match.correlation >= MIN_GEOMETRY_CORRELATION and match.iou >= 0.99, match


@pytest.mark.parametrize("name", ["shirt", "pull", "CesiumMan"])
def test_display_color_layer_shows_the_amplitude_in_storm(bake_views, name):
    """With usdview's defaults (materials on) Storm shows the display-colour layer's
    viridis ramp, bound for the preview purpose over the mesh's own material: its hue
    follows the amplitude that usdwrinkle renders for regular folds, pixel by pixel (the
    layer holds one amplitude per vertex; irregular folds vary within a fold: against the
    irregular frame, at the fallback 0.15, the pulled sheet scored -0.82 and CesiumMan
    -0.9496)."""
    from realclients.bakes import display_ramp_order

    order, pixels = display_ramp_order(bake_views[name])
    assert pixels > 5000
    assert order <= -0.95, (name, order)


@pytest.mark.parametrize("name,least", [("shirt", 0.98), ("pull", 0.98), ("CesiumMan", 0.89)])
def test_display_color_layer_looks_the_same_in_usdwrinkle_and_storm(bake_views, name, least):
    """usdwrinkle draws the display-colour layer as Storm does: each corner's
    displayColor through the preview material's UsdPrimvarReader_float3 (it drew the
    clay default before, ignoring per-vertex colours). CesiumMan, lit by usdview's
    head-light only, measures 0.899 (0.913 before the fold law's amplitude ramp): the
    same ramp, brighter all over in Storm, and the arms' highlights differ. The
    cause is not found yet: the plain frame with his own material agrees at 0.997, and a
    glossy preview surface under the head-light alone agrees at 0.9994 (the
    headlight_glossy probe), so it is neither the head-light nor the surface."""
    from realclients.compare import compare

    views = bake_views[name]
    match = compare(views.images["ours_display"], views.images["storm_display"])
    print(name, match)
    assert match.correlation >= least and match.iou >= 0.99, match


# --- issue 23: the bake outputs as Cycles shows them -----------------------------------


@pytest.fixture(scope="module")
def cycles_shirt(realclient, tmp_path_factory):
    """Cycles' views of the shirt's maps: "triangle", one set per triangle (bake
    --tangent-space triangle), and "default", the default bake, whose all-purpose set
    Blender's importer takes: MikkTSpace in the asset's UVs (byte-identical to bake
    --tangent-space mikktspace --map-layout asset: test_maps.py)."""
    from realclients.bakes import ELBOW_SHOT, cycles_views

    return {name: cycles_views(ELBOW_SHOT, tmp_path_factory.mktemp(f"cycles_{name}"),
                               tangent_space=frame)
            for name, frame in (("triangle", "triangle"), ("default", None))}


def test_geometry_layer_normals_in_cycles(cycles_shirt):
    """Cycles (Blender's USD importer, render purpose) shades the geometry layer's
    displaced mesh with the normals usdwrinkle shades it with: its Normal pass against
    usdwrinkle's N AOV over the front faces (measured: median 0.09, p90 0.87, p99 4.2
    degrees, 0.80 and 3.8 before the deepened pleats; while the offset's normals were its
    interpolated gradients, not the gradient of the offset surface drawn, p99 7.0; the
    back faces: test_back_faces_in_cycles_follow_its_own_convention)."""
    from realclients.bakes import front_angles

    views = cycles_shirt["triangle"]
    degrees, mask = front_angles(*views["geometry"], views["backfacing"]["geometry"])
    assert mask.sum() > 40000
    median, p90, p99 = np.percentile(degrees[mask], [50, 90, 99])
    assert median <= 0.3 and p90 <= 1.5 and p99 <= 5.0, (median, p90, p99)


def _cycles_maps_angles(views):
    """(degrees, mask, lower third) of Cycles' maps normals against usdwrinkle's, both raw
    and with usdwrinkle's normals put through Cycles' reflection clamp."""
    from realclients.bakes import cycles_reflection_clamp, front_angles

    (ours, ours_mask), theirs = views["maps"]
    plain, plain_mask = views["plain"]
    clamped = cycles_reflection_clamp(ours, plain, views["view"])
    result = {}
    for label, normals in (("raw", ours), ("clamped", clamped)):
        degrees, mask = front_angles((normals, ours_mask & plain_mask), theirs,
                                     views["backfacing"]["maps"])
        lower = mask & (np.arange(mask.shape[0])[:, None] > 2 * mask.shape[0] // 3)
        result[label] = (np.percentile(degrees[mask], [50, 90, 99]),
                         np.percentile(degrees[lower], 99))
    return result


@pytest.mark.parametrize("frame,bounds", [
    # (raw: median, p90, p99, elbow p99; clamped: p90, p99, elbow p99), measured + margin
    ("triangle", (0.3, 6.0, 24.0, 31.0, 4.0, 19.0, 26.0)),  # 0.12, 4.09, 19.98, 27.12;
    #                                                         2.86, 15.32, 22.09
    ("default", (0.1, 2.0, 17.0, 23.0, 1.0, 9.0, 13.0)),  # 0.03, 1.39, 14.4, 19.34;
    #                                                       0.66, 6.87, 10.49
])
def test_maps_normals_in_cycles_as_measured(cycles_shirt, frame, bounds):
    """Cycles decodes the maps (Blender's USD importer, normal-map node), per triangle
    and the default bake's MikkTSpace set, against usdwrinkle's N AOV over the front
    faces (Cycles' Backfacing AOV; the back faces: the convention test below); issue 23
    asks for p99 <= 5 degrees at the elbow. Measured over the shirt at 640 pixels with
    its irregular folds (median, p90, p99; the lower third, the elbow's, p99): triangle
    0.12 / 4.09 / 19.98; 27.12; default (MikkTSpace) 0.03 / 1.39 / 14.4; 19.34.

    Most of what is left is not the frame: Cycles tilts any shading normal whose mirror
    reflection of the view would fall below the surface back toward the geometric normal
    (ensure_valid_specular_reflection), so normal-map wrinkles steeper than about 45
    degrees show shallower in Cycles (the cuff's crests and the elbow's pinch). With
    usdwrinkle's normals put through that clamp (our smooth normal standing in for
    Cycles' flat one): triangle p90 2.86, p99 15.32, elbow 22.09; default 0.66, 6.87,
    10.49. This test holds the measured values: the Normal pass is not the decoded
    normal (the test below measures that; the geometry layer meets the 5 degrees in the
    Normal pass: the test above). Until 2026-12-05 a 90-degree cut stood in for the
    back-face mask and let part of the sleeve's inside in (triangle raw p99 28.0,
    default 22.2, with regular waves). Measured with wrinkle:slack 0; with the fallback
    slack (0.06) the triangle maps had given raw p99 34.9 (elbow 35.5), in streaks along
    the coarse triangles' edges at the elbow's pinch (per-triangle frames), while Storm
    agrees better with it (p99 9.1 against 9.7)."""
    angles = _cycles_maps_angles(cycles_shirt[frame])
    (median, p90, p99), elbow = angles["raw"]
    assert median <= bounds[0] and p90 <= bounds[1] and p99 <= bounds[2] and \
        elbow <= bounds[3], angles
    (_, p90, p99), elbow = angles["clamped"]
    assert p90 <= bounds[4] and p99 <= bounds[5] and elbow <= bounds[6], angles


@pytest.mark.parametrize("frame,view,bounds", [
    # (median, p90, p99, elbow p99), measured + margin
    ("triangle", "decoded", (0.2, 3.5, 19.0, 26.0)),        # 0.09, 2.49, 15.0; 21.55
    ("default", "decoded", (0.1, 0.3, 1.5, 3.0)),           # 0.03, 0.17, 0.88; 1.94
    ("default", "decoded_per_pixel", (0.1, 0.5, 3.5, 5.0)),  # 0.03, 0.30, 2.37; 3.85
])
def test_maps_decoded_normals_in_cycles(cycles_shirt, frame, view, bounds):
    """Cycles' decoded normal itself: the output of the Normal Map node (a shader AOV,
    cycles_client's "decoded"), before the BSDF's reflection clamp that the Normal pass
    above includes, against usdwrinkle's N AOV over the front faces. Issue 23 asks for
    p99 <= 5 degrees at the elbow: the default bake's maps hold it (1.94, 2.25 before the
    horizon, 1.83 with regular waves; Blender takes its all-purpose set, MikkTSpace in
    the asset's UVs), per-triangle maps do not (21.6: Blender decodes them in its own
    frame).

    Two things make the MikkTSpace maps Blender's own (maps/tangents.py): the shirt is a
    catmullClark mesh without authored normals, so Blender makes its smooth normals
    itself, angle-weighted (11 degrees from Storm's and usdwrinkle's at p99 over the
    elbow's posed vertices), and the map is encoded about those; and mikktspace.c sums
    a quad's tangents over its split along the shorter UV diagonal, by posed length
    where the UV diagonals tie (a rectangle), not along 0-2. Without them: 0.10 / 2.29 /
    9.57, elbow 9.99.

    Against render's default, which shades every multisample where the folds turn
    within the pixel and so averages its normals over the pixel as Cycles' 16 samples
    do, the elbow's p99 is 1.94; "decoded_per_pixel", against render --no-shade-samples,
    3.85: measured (2026-12-06) without the pixels where usdwrinkle's draw turns a bent
    normal back to its horizon (realclients.bakes.horizon_turned), which the decoded map
    does not (with them, before the horizon, 2.25 and 4.11)."""
    from realclients.bakes import front_angles

    views = cycles_shirt[frame]
    degrees, mask = front_angles(*views[view], views["backfacing"]["maps"])
    assert mask.sum() > 40000
    lower = mask & (np.arange(mask.shape[0])[:, None] > 2 * mask.shape[0] // 3)
    median, p90, p99 = np.percentile(degrees[mask], [50, 90, 99])
    elbow = np.percentile(degrees[lower], 99)
    assert median <= bounds[0] and p90 <= bounds[1] and p99 <= bounds[2] and \
        elbow <= bounds[3], (median, p90, p99, elbow)


def test_back_faces_in_cycles_follow_its_own_convention(cycles_shirt):
    """Where the shirt's open cuff shows the sleeve's inside (about 1,100 pixels at 640),
    Cycles' decoded normal is usdwrinkle's turned by 180 degrees about the unwrinkled
    normal: Storm's preview surface and usdwrinkle keep a double-sided back face's
    tangent and bitangent and turn its normal, so a normal map's tilt reads the same from
    both sides, while Cycles' normal-map node decodes in the front face's frame and
    negates the result (svm_node_normal_map; realclients.bakes.cycles_back_face). As
    they are, the two lie 100 degrees apart there at the median (the band along the
    cuff's top edge that the maps tests above had cut at 90 degrees); so turned, they
    agree (measured over 1,084 pixels: median 0.03, p90 0.25, p99 0.51 degrees on the
    default bake's maps). The geometry layer, without a normal map, turns the same way in
    both: its back faces agree as they are (769 pixels: median 0.14, p90 1.6 degrees)."""
    from realclients.bakes import back_angles, cycles_back_face

    views = cycles_shirt["default"]
    (ours, ours_mask), theirs = views["decoded"]
    plain, plain_mask = views["plain"]
    back = views["backfacing"]["maps"]
    as_is, mask = back_angles((ours, ours_mask & plain_mask), theirs, back)
    turned, _ = back_angles((cycles_back_face(ours, plain), ours_mask & plain_mask),
                            theirs, back)
    assert mask.sum() > 800, mask.sum()
    median, p90 = np.percentile(turned[mask], [50, 90])
    assert median <= 0.1 and p90 <= 1.0, (median, p90)
    assert np.median(as_is[mask]) >= 90.0
    geometry, mask = back_angles(*views["geometry"], views["backfacing"]["geometry"])
    assert mask.sum() > 500, mask.sum()  # 769: the displaced cuff's rim hides more of it
    median, p90 = np.percentile(geometry[mask], [50, 90])
    assert median <= 0.3 and p90 <= 2.5, (median, p90)


def test_blender_imports_the_full_map_set_with_the_full_look(realclient, tmp_path):
    """Blender's USD importer resolves material:binding:full, else the all-purpose binding,
    and ignores the preview purpose: the shirt binding a look per purpose (all red, full
    blue, preview green; tests/helpers.bind_purpose_looks), baked with the default maps,
    imports with the full set's material (MikkTSpace maps) and the full look (blue), never
    the preview set's (per-triangle islands maps, which Cycles decodes at p99 81 degrees).
    Without the full binding that the bake adds, Blender would keep the blue material
    and show no wrinkles."""
    import json

    from pxr import Sdf, Usd

    from realclients import blender_import
    from realclients.shots import SAMPLES
    from usdwrinkle.cli.main import main

    from helpers import bind_purpose_looks

    shot = tmp_path / "shot.usda"
    root = Sdf.Layer.CreateNew(str(shot))
    root.subLayerPaths = [str(SAMPLES / "shirt.usda")]
    root.Save()
    stage = Usd.Stage.Open(str(shot))
    bind_purpose_looks(stage, "/World/Arm/Sleeve")
    stage.Save()
    layer = tmp_path / "maps.usda"
    assert main(["bake", str(shot), str(layer), "--quiet", "--frames", "24", "--maps",
                 "normal", "--map-size", "256"]) == 0
    out = tmp_path / "imported.json"
    results = blender_import([{"stage": str(layer), "out": str(out)}])
    assert results[str(out)] == "ok", results
    sleeve = json.loads(out.read_text())["Sleeve"]
    assert sleeve == {"materials": ["Sleeve"], "normal_images": ["Sleeve.normal.0024.png"],
                      "base_colours": [[0.0, 0.0, 1.0, 1.0]], "image_sequences": []}, sleeve


def test_mikktspace_matches_blenders_calc_tangents(realclient, tmp_path):
    """usdwrinkle's vectorised MikkTSpace (maps/tangents.py) against Blender's
    Mesh.calc_tangents on a noisy sleeve with a UV seam and a mirrored island: the same
    tangents (Blender's custom normals are stored compressed, within 0.4 degrees) and the
    same signs."""
    from realclients import blender_tangents
    from usdwrinkle.maps.tangents import mikktspace

    rng = np.random.default_rng(3)
    around, along = 24, 12
    angle = np.arange(around) / around * 2 * np.pi
    rows = np.linspace(0.0, 2.0, along + 1)
    points = np.stack(np.broadcast_arrays(np.cos(angle)[None, :], np.sin(angle)[None, :],
                                          rows[:, None]), -1).reshape(-1, 3)
    points = points + rng.normal(0.0, 0.03, points.shape)
    triangles, uv = [], []
    for r in range(along):
        for c in range(around):
            quad = [(r, c), (r, c + 1), (r + 1, c + 1), (r + 1, c)]
            quad_uv = [(cc / around, rr / along) for rr, cc in quad]
            if r >= along // 2:   # the upper half mirrored in s
                quad_uv = [(1.0 - s, t) for s, t in quad_uv]
            for corners in ((0, 1, 2), (0, 2, 3)):
                triangles.append([rr * around + cc % around
                                  for rr, cc in (quad[k] for k in corners)])
                uv += [quad_uv[k] for k in corners]
    triangles, uv = np.array(triangles), np.array(uv, np.float32)
    face = np.cross(points[triangles[:, 1]] - points[triangles[:, 0]],
                    points[triangles[:, 2]] - points[triangles[:, 0]])
    normals = np.zeros_like(points)
    np.add.at(normals, triangles.reshape(-1), np.repeat(face, 3, axis=0))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    mesh, out = tmp_path / "mesh.npz", tmp_path / "tangents.npz"
    np.savez(mesh, points=points.astype(np.float32), triangles=triangles,
             normals=normals[triangles.reshape(-1)].astype(np.float32), uv=uv)
    assert blender_tangents([{"mesh": str(mesh), "out": str(out)}]) == {str(out): "ok"}
    blender = np.load(out)
    # with the normals Blender used, so that its compression does not count
    ours = mikktspace(points, triangles, blender["normal"], uv)
    degrees = np.degrees(np.arccos(np.clip(np.sum(ours[:, :3] * blender["tangent"], 1),
                                           -1, 1)))
    assert np.percentile(degrees, 99) < 0.1 and degrees.max() < 0.5, degrees.max()
    assert (ours[:, 3] == blender["sign"]).all() and (blender["sign"] < 0).any()
    # and not a vacuous match: the per-triangle frame is far from Blender's
    ours_triangle = mikktspace(points, triangles, blender["normal"], uv,
                               (np.arange(3 * len(triangles)), ours[::3, 3] > 0))
    apart = np.degrees(np.arccos(np.clip(np.sum(ours_triangle[:, :3] * blender["tangent"],
                                                1), -1, 1)))
    assert np.percentile(apart, 50) > 2.0
