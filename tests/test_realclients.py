"""The real-client tier: usdwrinkle's frames against usdview's Storm, rendered headless
from Blender's bpy wheel (realclients/). Marker ``realclient``; without a Python that has
bpy these tests are skipped with the reason, and the run's summary says the tier did not
run (``--require-realclients``, which .ci/run passes, makes that an error).

Cost on this 2-core machine: about 60 s for the plain frames (8 shots x 2 frames, both
renderers at 320 pixels) and 15 s for the probes.
"""
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
                                  "translucent"])
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
