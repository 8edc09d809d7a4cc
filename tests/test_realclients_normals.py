"""The real-client tier, continued: the shading normals that usdview's Storm decodes from
usdwrinkle's wrinkle maps, against usdwrinkle's own, by photometric stereo (issue 23). A
file of its own so that a run on several cores (pytest-xdist, ``--dist loadfile``) gives
these seven cases, about 3 minutes on this 2-core machine, a worker beside the rest of the
tier (test_realclients.py)."""
from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.realclient

#: each side's decoded normals by what they depend on (realclients.bakes.normal_views):
#: the four 640-pixel cases share usdwrinkle's renders at slack 0, the 1280-pixel ones
#: share them too, and two of those share Storm's (about a minute of the tier's three)
_DECODED: dict = {}


@pytest.mark.parametrize("frame,slack,layout,width,options,bounds", [
    # measured against render's default (the multisamples of wrinkled pixels shaded),
    # without the pixels it turns to the horizon (2026-12-06; the docstring):
    # median, p90, p99; the elbow's p99 (2026-12-05, with the stage's irregular folds,
    # wrinkle:irregularity 0.15; with regular waves, 2026-11-27: 0.44, 1.39, 8.43; 12.6 /
    # 0.47, 3.11, 19.9; 26.7 / 0.48, 1.35, 8.08; 11.6 / 0.34, 1.18, 5.33; 9.33 / 0.17,
    # 0.42, 1.47; 2.68 / 0.17, 0.45, 1.96; 3.68 / 0.09, 0.31, 1.39; 2.64)
    ("triangle", 0.0, "asset", 640, {}, (0.6, 1.8, 10.0, 15.0)),     # 0.33, 1.10, 7.39; 10.41
    ("mikktspace", 0.0, "asset", 640, {}, (0.7, 4.0, 23.0, 30.0)),   # 0.37, 2.74, 17.45; 24.74
    ("triangle", None, "asset", 640, {}, (0.6, 1.8, 10.0, 14.0)),    # 0.45, 1.07, 6.88; 9.75
    ("triangle", 0.0, "islands", 640, {}, (0.5, 1.6, 7.0, 11.5)),    # 0.24, 0.87, 4.03; 6.66
    # issue 23's 3 degrees at the elbow, at 1280 pixels: the default bake, whose preview
    # set (per triangle, islands; byte-identical to "triangle", "islands": test_maps.py)
    # Storm shows
    (None, 0.0, None, 1280, {}, (0.25, 0.6, 2.0, 3.0)),             # 0.16, 0.36, 1.20; 2.15
    # against render --no-shade-samples (each pixel shaded once)
    (None, 0.0, None, 1280, {"shade_samples": False},
     (0.3, 0.7, 2.5, 4.3)),                                       # 0.16, 0.37, 1.51; 2.68
    # EXR maps (Storm reads a 16-bit PNG at 8 bits)
    (None, 0.0, None, 1280, {"map_format": "exr"},
     (0.15, 0.5, 2.0, 3.0)),                                      # 0.08, 0.23, 1.17; 2.13
])
def test_maps_decoded_normals_in_storm(realclient, tmp_path, frame, slack, layout, width,
                                       options, bounds):
    """The shading normals Storm decodes from the maps against usdwrinkle's, both by
    photometric stereo (six renders, one distant light each along +-X, +-Y, +-Z), for
    each tangent frame of --tangent-space: median, p90 and p99 over the shirt at 640
    pixels, and p99 in the lower third (the elbow's crease). Issue 23 asks for p99 <= 3
    degrees at the elbow.

    Storm builds the per-triangle frame, so "triangle" is its own: what is left lies in
    one-pixel lines along the coarse triangles' edges (the p99 halves at 1280 pixels, to
    4.5): Storm shades its four multisamples at the pixel's centre, so an edge pixel
    samples the neighbouring triangle's texels and decodes them in its own triangle's
    frame, which turns by 29 degrees (median) across the elbow's quads. A MikkTSpace map
    decoded in Storm's frame is off by the frames' difference (10 degrees median at the
    elbow) times the tilt. This test holds the measured values, so that a change for
    the worse fails.
    ``slack`` None keeps the fallback wrinkle:slack (the other comparisons author 0):
    Storm agrees as well with it.

    --map-layout islands (maps/islands.py) removes both causes: no face reads another's
    texels, and a quad's frame is one across its diagonal. What is left at 640 pixels is
    texture filtering of the elbow's pinch, whose folds are a few pixels across: usdwrinkle
    drawing the very same islands map differs from Storm by 9.8 degrees at the elbow's
    p99 (llvmpipe's filtering against usdwrinkle's GPU-style one), and its analytic
    band limit from its own drawing of the map by 5.4. At 1280 pixels, shaded once per
    pixel, the islands miss the 3 degrees only at the grazing fold contours (2.8 without
    the pixels within one of |n.v| < 0.1); the asset's UVs give 0.27 / 0.55 / 4.43 and
    7.5 there.

    What is left at 1280 pixels lies at the elbow's pinch, where the folds' normals turn
    within a pixel: Storm's texture filtering averages the map over the pixel. usdwrinkle
    shades each multisample where it lies wherever the folds turn within the pixel
    (render's default), so it averages over the
    pixel too, and issue 23's 3 degrees holds there (2.55; shaded once per pixel, render
    --no-shade-samples, 3.34). Storm reads a 16-bit PNG at 8 bits (its frames of the
    16-bit map and of the same map rounded to 8 bits differ by 0.02 degrees median, of an
    EXR by 0.09), so EXR maps halve the median (0.16 -> 0.09). At 640 pixels the elbow
    is 9.2 (11.8 shaded once per pixel).

    Since 2026-12-06 the pixels where usdwrinkle's draw turns a bent normal back to its
    horizon (contract.HORIZON_COSINE), which a normal map, the same for every view,
    cannot, are left out (realclients.bakes.horizon_turned); the values beside the cases
    are measured so (the default bake's elbow at 1280 pixels 2.15, 2.68 shaded once per
    pixel; with them, 2.55 and 3.34 had been measured before the horizon, whose turned
    normals failed the 1280-pixel cases: p99 3.4-3.8, elbow 5.4-6.0)."""
    import dataclasses

    from realclients.bakes import ELBOW_SHOT, angles, normal_views

    shot = dataclasses.replace(ELBOW_SHOT, width=width)
    views = normal_views(shot, tmp_path, tangent_space=frame, slack=slack, layout=layout,
                         memo=_DECODED, **options)
    degrees, mask = angles(views["usdwrinkle"], views["storm"])
    assert mask.sum() > 40000 * (width / 640) ** 2
    lower = mask & (np.arange(mask.shape[0])[:, None] > 2 * mask.shape[0] // 3)
    median, p90, p99 = np.percentile(degrees[mask], [50, 90, 99])
    elbow = np.percentile(degrees[lower], 99)
    assert median <= bounds[0] and p90 <= bounds[1] and p99 <= bounds[2] and \
        elbow <= bounds[3], (median, p90, p99, elbow)
