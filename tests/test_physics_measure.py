"""The cloth oracle's measurements (benchmarks/physics/measure.py, coarse.py) on analytic
fields: a plane wave's wavelength, direction and phase motion, and a low-pass that keeps
a smooth bend while it removes folds. The oracle itself needs Blender (docs/physics.md)."""
from __future__ import annotations

import numpy as np
import pytest

from benchmarks.physics import measure
from benchmarks.physics.coarse import lowpass
from benchmarks.physics.shots import Shot, sheet


def flat_shot(rows=65, cols=97, spacing=0.01) -> Shot:
    u = np.arange(cols) * spacing
    v = np.arange(rows) * spacing
    U, V = np.meshgrid(u, v)
    rest = np.stack([U, np.zeros_like(U), -V], -1).reshape(-1, 3)
    return Shot("flat", rows, cols, False, rest, np.stack([U, V], -1).reshape(-1, 2),
                np.zeros(rows * cols, bool), 1, False)


@pytest.mark.parametrize("wavelength, angle", [(0.07, 0.0), (0.09, 30.0), (0.05, 90.0)])
def test_a_plane_wave_s_wavelength_and_direction(wavelength, angle):
    shot = flat_shot()
    direction = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
    h = 0.01 * np.cos(2 * np.pi / wavelength * shot.material @ direction)
    assert measure.wavelength(shot, h) == pytest.approx(wavelength, rel=0.05)
    assert measure.angle_between(measure.structure_direction(shot, h), direction) < 1.5
    inner = measure.amplitude_field(shot, h).reshape(shot.rows, shot.cols)[15:-15, 15:-15]
    np.testing.assert_allclose(inner, 0.01, rtol=0.05)   # a sine's local amplitude


@pytest.mark.parametrize("second", [None, 0.10, 0.14])
def test_the_spectral_spread_of_one_wave_and_of_two(second):
    """measure.spectral_spread: sqrt(<f^2>) / <f> of the power spectrum, 1 for one plane
    wave and sqrt((f1^2 + f2^2) / 2) / ((f1 + f2) / 2) for two of equal power."""
    shot = flat_shot()
    x = shot.material[:, 0]
    h = np.cos(2 * np.pi / 0.05 * x)
    f1, f2 = 1 / 0.05, 1 / 0.05
    if second is not None:
        h = h + np.cos(2 * np.pi / second * x)
        f2 = 1 / second
    expected = np.sqrt((f1 ** 2 + f2 ** 2) / 2) / ((f1 + f2) / 2)
    assert measure.spectral_spread(shot, h) == pytest.approx(expected, abs=0.003)


def test_crest_motion_is_the_phase_change_a_frame():
    shot = flat_shot()
    k = 2 * np.pi / 0.07 * np.array([1.0, 0.0])
    h = np.stack([0.01 * np.cos(shot.material @ k - 0.1 * f) for f in range(4)])
    mask = np.ones(len(shot.material), bool)
    assert measure.crest_motion(shot, h, mask, range(3)) == pytest.approx(0.1, rel=0.02)
    still = np.stack([h[0]] * 4)
    assert measure.crest_motion(shot, still, mask, range(3)) < 1e-9


def test_the_low_pass_keeps_a_bend_and_removes_folds():
    """A sheet bent on a radius of 20 cm with 7 cm folds on it: the twiced low-pass stays
    within 2 mm of the bend (a plain Gaussian of 5 cm sags 7 mm inwards) and
    keeps under 2% of the folds' height."""
    shot = sheet()
    u = shot.material[:, 0]
    radius = 0.2
    angle = (u - u.mean()) / radius
    bent = shot.rest.copy()
    bent[:, 0] = radius * np.sin(angle)
    bent[:, 1] = radius * (1 - np.cos(angle))
    normal = np.stack([-np.sin(angle), np.cos(angle), np.zeros_like(angle)], 1)
    folds = 0.01 * np.cos(2 * np.pi * u / 0.07)[:, None] * normal
    smooth = lowpass(shot, (bent + folds)[None])[0]
    inner = (shot.material[:, 0] > 0.15) & (shot.material[:, 0] < 0.8)
    assert np.abs(smooth - bent)[inner].max() < 2e-3
    # the filter is linear in the displacement: what it keeps of the folds alone
    kept = smooth - lowpass(shot, bent[None])[0]
    assert np.linalg.norm(kept, axis=1)[inner].max() < 0.02 * 0.01


def test_the_low_pass_keeps_a_rotated_end_at_its_border():
    """The sleeve's forearm end turns with the arm: a displacement that grows linearly
    towards an open border. The local-linear low-pass keeps such a ramp to the border (the
    coarse mesh's end ring stays on the pinned ring, and the simulation's fold height there
    is 0); the twiced renormalised Gaussian it replaced pulled the border 2.3 cm towards
    the body (for a slope of 1.4: a quarter turn)."""
    from benchmarks.physics.coarse import _smooth_axis

    shot = flat_shot()
    v = shot.material[:, 1]
    turned = shot.rest.copy()
    turned[:, 1] += 1.4 * v              # out of plane, growing towards the last row
    smooth = lowpass(shot, turned[None])[0]
    np.testing.assert_allclose(smooth, turned, atol=1e-9)
    ramp = 1.4 * 0.01 * np.arange(65.0)
    once = _smooth_axis(ramp, 0, 5.0, False, linear=False)
    twiced = once + _smooth_axis(ramp - once, 0, 5.0, False, linear=False)
    assert ramp[-1] - twiced[-1] > 0.02    # what the renormalised average did at the end
    np.testing.assert_allclose(_smooth_axis(ramp, 0, 5.0, False, linear=True), ramp,
                               atol=1e-12)


def test_the_curvature_fit_recovers_a_power_law():
    """Tubes folding as 0.05 (R / 0.23)^0.5 give back p = 0.5 and R_c = 0.23; the product's
    curved_width with the schema's constants (theory's 1/2 power through the converged
    referee's sleeves, whose folds do not coarsen: 7.7 cm at 10 cm, docs/physics.md) is
    min(flat, 0.077 (R / 0.10)^0.5), whichever the cloth's flat width."""
    from benchmarks.physics.__main__ import curvature_fit
    from usdwrinkle.scene.params import curved_below, curved_width
    from usdwrinkle.usd import schema

    radii = np.array([0.06, 0.10, 0.15])
    wavelengths = 0.05 * (radii / 0.23) ** 0.5
    exponent, radius = curvature_fit(radii, wavelengths, 0.05)
    assert exponent == pytest.approx(0.5, abs=1e-9) and radius == pytest.approx(0.23, rel=1e-9)
    assert (schema.CURVED_EXPONENT, schema.CURVED_WIDTH_M, schema.CURVED_RADIUS_M) == \
        (0.5, 0.077, 0.10)
    tube = 0.077 * (radii / 0.10) ** 0.5
    for flat in (0.054, 0.084, 0.2):
        np.testing.assert_allclose(curved_width(flat, 1.0 / radii), np.minimum(flat, tube),
                                   rtol=1e-12)
        below = curved_below(flat)
        assert float(curved_width(flat, np.array([1.0 / below]))[0]) == pytest.approx(flat)
    np.testing.assert_allclose(curved_width(0.084, np.array([0.0, 1.0, 100.0])),
                               [0.084, 0.084, 0.077 * (0.02 / 0.10) ** 0.5], rtol=1e-12)




@pytest.mark.parametrize("name", ["curtain-leather", "sleeve10-silk", "shear-cotton"])
def test_the_sweep_bakes_each_shot_with_its_own_cloth(tmp_path, name):
    """The referee's sweep (benchmarks/physics/referee.py) compares usdwrinkle at the
    default W of each shot's preset: the stage it bakes resolves, through usdwrinkle's own
    parameter reading, to the W its table prints (until 2026-12-02 the stages named no
    cloth, and silk and leather shots were baked at cotton's W)."""
    from pxr import Usd, UsdGeom

    from benchmarks.physics.referee import SPACING, SWEEP, cloth_attributes, default_width
    from benchmarks.physics.stage import MESH, write_stage
    from usdwrinkle.scene.params import read_params
    from usdwrinkle.scene.topology import build_topology

    shot = SWEEP[name](SPACING).shot
    path = str(tmp_path / "shot.usda")
    write_stage(path, shot, shot.rest[None].repeat(2, axis=0),
                attributes=cloth_attributes(shot))
    stage = Usd.Stage.Open(path)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath(MESH))
    rest = np.asarray(mesh.GetPointsAttr().Get(0), np.float64)
    topology = build_topology(np.asarray(mesh.GetFaceVertexCountsAttr().Get()),
                              np.asarray(mesh.GetFaceVertexIndicesAttr().Get()), rest)
    width = read_params(mesh.GetPrim(), rest, topology).width
    assert float(np.median(width)) == pytest.approx(default_width(shot), rel=1e-3)


@pytest.mark.parametrize("make", ["curtain", "sleeve5", "sleeve10", "shear"])
def test_the_converged_referee_is_resampled_onto_the_sweep_grid(make):
    """The 2 cm simulations (referee.CONVERGED) are baked on the 1 cm grid: sweep.resample
    keeps the simulated points and puts one half-way between neighbours with the four-point
    cubic, exact for cubics along a flat grid and within 30 µm of the 5 cm sleeve's circle.
    A fold of 3 samples a wavelength comes out at the cubic's response, (9 cos(pi/3) -
    cos(pi)) / 8 = 0.6875 of its height half-way: why the referee measures heights at the
    simulation's own points (referee.bake_on), not on the resampled grid."""
    from benchmarks.physics import sweep

    maker = {"curtain": lambda h: sweep.curtain("cotton", h),
             "sleeve5": lambda h: sweep.sleeve("cotton", h, 0.05),
             "sleeve10": lambda h: sweep.sleeve("cotton", h, 0.10),
             "shear": lambda h: sweep.shear("cotton", h)}[make]
    coarse, fine = maker(0.02), maker(0.01)
    out = sweep.resample(coarse.clean[None], coarse, fine)[0]
    assert out.shape == fine.clean.shape
    assert np.abs(out - fine.clean).max() < (3e-5 if make == "sleeve5" else 5e-6)
    # a fold 6 cm long along the material's v (3 samples a wavelength at 2 cm), its
    # crests at every third 2 cm row
    v = coarse.shot.material[:, 1]
    fold = 0.005 * np.cos(2 * np.pi / 0.06 * v)
    moved = coarse.clean + fold[:, None] * np.array([0.0, 0.0, 1.0])
    grid = sweep.resample(moved[None], coarse, fine)[0].reshape(fine.shot.rows,
                                                                 fine.shot.cols, 3)
    np.testing.assert_allclose(grid[::2, ::2],
                               moved.reshape(coarse.shot.rows, coarse.shot.cols, 3), atol=1e-12)
    rest = fine.clean.reshape(grid.shape)
    truth = 0.005 * np.cos(2 * np.pi / 0.06 * fine.shot.material[:, 1]).reshape(grid.shape[:2])
    half_way = (grid - rest)[1:-1:2, :, 2][2:-2]      # odd rows, away from the ends
    np.testing.assert_allclose(half_way, 0.6875 * truth[1:-1:2][2:-2], atol=1e-9)
    with pytest.raises(ValueError, match="half the spacing"):
        sweep.resample(coarse.clean[None], coarse, maker(0.005))


@pytest.mark.parametrize("wavelength", [0.08, 0.24])
def test_the_referee_widens_its_window_for_long_folds(wavelength):
    """referee.fold_window: the measure's Gaussian stays WINDOW (5 cm) for short folds and
    widens for long ones to FOLD_WINDOW (0.43) times the wavelength it measures, where the
    twiced low-pass keeps 2G - G^2 = 5% of the fold, G = exp(-2 pi^2 0.43^2). A 24 cm fold
    keeps 1 - (1 - 0.42)^2 = 66% of its height in the 5 cm low-pass, which is how the
    leather curtain's long folds were measured short."""
    from benchmarks.physics import referee, sweep

    made = sweep.curtain("cotton", 0.02)
    shot = made.shot
    u = shot.material[:, 0]
    fold = 0.01 * np.cos(2 * np.pi / wavelength * u)
    points = np.repeat((shot.rest + fold[:, None] * np.array([0.0, 1.0, 0.0]))[None],
                       shot.frames, axis=0)
    window = referee.fold_window(shot, points)
    assert shot.window == window
    def kept(sigma: float) -> float:
        """The most of the fold the low-pass keeps, 3 sigma in from the sides (where it is
        the plain Gaussian)."""
        inner = (u > u.min() + 3 * sigma) & (u < u.max() - 3 * sigma)
        low = lowpass(shot, points[:1], sigma)[0]
        return float(np.abs(low - shot.rest)[inner, 1].max() / 0.01)

    if wavelength < 0.1:
        assert window == referee.WINDOW
        assert kept(window) < 0.05
    else:
        assert window == pytest.approx(referee.FOLD_WINDOW * wavelength, rel=0.05)
        assert kept(referee.WINDOW) == pytest.approx(0.66, abs=0.05)
        # the twiced Gaussian's transfer at the window found (its wavelength is measured
        # within 5%, so the share kept lies near 5%, not on it)
        g = np.exp(-2 * np.pi ** 2 * (window / wavelength) ** 2)
        assert kept(window) == pytest.approx(1 - (1 - g) ** 2, abs=0.005)
        assert kept(window) < 0.08
        assert referee.mean_wavelength(shot, measure.sim_height(shot, points)) == \
            pytest.approx(wavelength, rel=0.05)


@pytest.mark.parametrize("samples", [4.0, 5.5, 11.0])
def test_a_sampled_fold_keeps_sinc_squared_of_its_extra_length(samples):
    """referee.area_grid's reason: a fold sampled at n points a wavelength, as a displaced
    mesh draws it, keeps about sinc(pi / n)^2 of the extra length of the continuous fold
    (averaged over its phase against the samples). The 10 cm sleeves' W (5.5 cm) on the 1
    cm grid kept 0.89 of it; on the 0.5 cm grid, which usdwrinkle's geometry bake would
    choose (6 samples a wavelength at least), 0.97."""
    wavelength, amplitude = 1.0, 0.02
    k = 2 * np.pi / wavelength
    extra = (amplitude * k) ** 2 / 4          # the continuous fold's, to second order
    kept = []
    for offset in np.linspace(0.0, 1.0, 16, endpoint=False):
        x = (np.arange(int(40 * samples) + 1) + offset) * wavelength / samples
        h = amplitude * np.sin(k * x)
        length = np.hypot(np.diff(x), np.diff(h)).sum() / (x[-1] - x[0])
        kept.append((length - 1.0) / extra)
    sinc = np.sin(np.pi / samples) / (np.pi / samples)
    assert np.mean(kept) == pytest.approx(sinc ** 2, rel=0.01)


def test_the_area_is_taken_where_w_is_sampled_six_times():
    from benchmarks.physics.referee import SPACING, area_grid
    from usdwrinkle.geometry.options import DEFAULT_SAMPLES_PER_WAVELENGTH

    assert DEFAULT_SAMPLES_PER_WAVELENGTH == 6.0
    assert area_grid(0.09) == SPACING             # the curtains: 9 samples at 1 cm
    assert area_grid(0.055) == SPACING / 2        # the 10 cm sleeves
    assert area_grid(0.039) == SPACING / 2        # the 5 cm sleeve: 7.8 at 0.5 cm
    assert area_grid(0.025) == SPACING / 4
    # where the folds do not coarsen (cap 1), W / 1.5 is sampled 6 times: 9 samples of W
    assert area_grid(0.09, 1.0) == SPACING        # 0.06 / 6 = 1 cm
    assert area_grid(0.0825, 1.0) == SPACING / 2  # the 10 cm sleeves at their matched W
    assert area_grid(0.0825, 1.5) == area_grid(0.0825)


@pytest.mark.parametrize("length", [1.2, 1.46, 1.86])
def test_a_profile_s_shape_against_the_zigzag_and_the_box(length):
    """benchmarks.physics.section's profile_shape, by hand: the triangle is the zigzag (1);
    a cosine holding length L has amplitude A with mean sqrt(1 + A^2 sin^2) = L, RMS
    A / sqrt 2; the upright box (heads at +-A, length 1 + 4 A per wavelength) is
    sqrt(3 (L - 1) / (L + 1)) the zigzag's, and steep tanh boxes approach it from above."""
    from benchmarks.physics.section import box_shape, profile_shape, zigzag_rms

    triangle = profile_shape(lambda t: (2 / np.pi) * np.arcsin(np.cos(t)), length)
    assert triangle == pytest.approx(1.0, abs=1e-3)
    # the cosine by its own quadrature: bisect A in sum sqrt(1 + A^2 sin^2 t) / n = L
    t = np.linspace(0.0, 2 * np.pi, 200001)[:-1]
    low, high = 0.0, 50.0
    for _ in range(80):
        a = 0.5 * (low + high)
        low, high = (low, a) if np.mean(np.sqrt(1 + a * a * np.sin(t) ** 2)) > length \
            else (a, high)
    cosine = 0.5 * (low + high) / (2 * np.pi) / np.sqrt(2) / zigzag_rms(length)
    assert profile_shape(np.cos, length) == pytest.approx(cosine, rel=1e-4)
    upright = np.sqrt(3 * (length - 1) / (length + 1))
    assert box_shape(length) == pytest.approx(upright, rel=1e-12)
    steep = profile_shape(lambda t: np.tanh(100 * np.cos(t)) / np.tanh(100), length)
    assert upright < steep < 1.1 * upright


@pytest.mark.parametrize("fold", [0.03, 0.06])
def test_the_elbow_fold_table_reads_a_known_accordion(fold):
    """benchmarks.physics.elbow.fold_table on the shirt's sleeve shot with folds put in by
    hand: rings of a known material wavelength, 2 mm high, and the whole sleeve gathered
    along its axis to r = 0.8; the table reads r = 0.8 and the wavelength back, over the
    band and over its (tapered) inner third."""
    from benchmarks.physics.elbow import fold_table, shirt_sleeve

    sweep_shot, sim_frame = shirt_sleeve("cotton", shirt_frames=range(1, 3))
    shot = sweep_shot.shot
    clean = sweep_shot.clean            # the sleeve's smooth rest surface (m), x along it
    axis = clean[:, 0] - clean[:, 0].min()
    radial = clean.copy()
    radial[:, 0] = 0.0
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    along = shot.material[:, 1]
    points = clean + 0.002 * np.sin(2 * np.pi * along / fold)[:, None] * radial
    points[:, 0] = clean[:, 0].min() + 0.8 * axis
    frames = np.repeat(points[None], max(sim_frame.values()), axis=0)
    for row in fold_table(shot, frames, sim_frame, [1, 2]):
        for name in ("band", "inner"):
            r, least, wavelength, height = row[name]
            assert r == pytest.approx(0.8, abs=0.01) and least == pytest.approx(0.8, abs=0.01)
            assert wavelength == pytest.approx(fold, rel=0.08)  # the measure: 5.6 cm at 6
            assert height == pytest.approx(0.002 / np.sqrt(2), rel=0.1)


def test_the_referee_s_sleeves_do_not_coarsen_and_its_curtains_do():
    """referee.coarsening_of: the cap usdwrinkle gives a sweep shot's cloth, worked out
    from the tube's wavelength at the sleeve's radius (7.7 cm at 10 cm, 5.4 cm at 5 cm):
    1 at the matched widths (7-8 cm and 5 cm), 1.5 where W is under 0.75 of it, and None
    (COARSENING_MAX) on flat cloth."""
    from benchmarks.physics.referee import SWEEP, coarsening_of

    sleeve10 = SWEEP["sleeve10-cotton"](0.02).shot
    sleeve5 = SWEEP["sleeve5-cotton"](0.02).shot
    assert coarsening_of(sleeve10, 0.076) == pytest.approx(1.0)
    assert coarsening_of(sleeve5, 0.050) == pytest.approx(1.0)
    assert coarsening_of(sleeve10, 0.05) == pytest.approx(1.5)
    assert coarsening_of(SWEEP["curtain-cotton"](0.02).shot, 0.09) is None


@pytest.mark.parametrize("along", [0.0, 0.008])
def test_the_height_field_scale_of_a_fold_that_leans(along):
    """benchmarks.physics.heightfield on a sheet pushed to 0.75 of its width into a
    trochoid, (x + b cos kx, a sin kx): the cloth's area, its low-pass's and the scale s
    at which its offsets along the low-pass's normals alone (a plain sine) hold the
    trochoid's length, against the curves' arc lengths integrated in 1D. Upright (b = 0)
    the cloth is its own height field (s = 1); leaning (b k = 0.84), its offsets along
    the surface hold length that the sine must stand 1.094 times as tall for; and the scale
    at which the sine holds the area bar's lowest area, 0.95 of the rest."""
    from benchmarks.physics.heightfield import phase_row

    shot = flat_shot(rows=33, cols=129, spacing=0.005)
    shot.pinned[shot.material[:, 0] == 0.0] = True   # the pushed edge
    push, height, k = 0.75, 0.008, 2 * np.pi / 0.06
    u, v = shot.material[:, 0], shot.material[:, 1]
    theta = k * push * u
    points = np.stack([push * u + along * np.cos(theta), height * np.sin(theta), -v], -1)
    row = phase_row(shot, points, 0.05)

    t = np.linspace(0.0, 2 * np.pi, 4096, endpoint=False)
    cloth = np.hypot(1 - along * k * np.sin(t), height * k * np.cos(t)).mean()

    def sine(scale):
        return np.hypot(1.0, scale * height * k * np.cos(t)).mean()

    def holding(length):
        low, high = 0.5, 4.0
        for _ in range(60):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if sine(middle) < length else (low, middle)
        return low

    low = holding(cloth)
    assert row["low"] == pytest.approx(push, rel=0.01)
    assert row["cloth"] == pytest.approx(push * cloth, rel=0.01)
    assert row["offsets"] == pytest.approx(push * sine(1.0), rel=0.01)
    assert row["s"] == pytest.approx(low, abs=0.015)   # 1.0 upright, 1.094 leaning
    # the area bar's edge, 0.95 of the rest area: the sine's arc factor 0.95 / push
    assert row["s edge"] == pytest.approx(holding(0.95 / push), abs=0.015)
    assert row["beyond"] == 0.0


def test_the_converged_table_is_the_referee_s_grids_and_presets():
    """docs/physics.md's converged table ("usdwrinkle against the converged referee") is
    made by `python -m benchmarks.physics.referee --tables converged --write`: each row's
    grid is the one referee.referee_grid judges the shot on (CONVERGED, CONVERGED_FINER)
    and its default W the one usdwrinkle gives the shot now (the preset through the
    curvature law). A preset refitted, or a shot moved to its 1 cm run, without the table
    made again fails here (the leather preset moved 16.8 -> 12.0 cm on 2026-12-06)."""
    from benchmarks.physics.referee import ROOT, SWEEP, default_width, kept_rows, referee_grid

    doc = (ROOT / "docs" / "physics.md").read_text()
    for name, make in SWEEP.items():
        kept = kept_rows(doc, "converged", name)
        assert kept is not None, name
        cells = [c.strip() for c in kept[0].strip("|").split("|")]
        grid = referee_grid(name, True)
        assert cells[2] == f"{100 * grid:g} cm", name
        printed = float(cells[4].split(",")[0])
        assert printed == pytest.approx(100 * default_width(make(grid).shot), abs=0.051), name


def test_the_correlation_s_parts_on_folds_that_fall_down_the_curtain():
    """benchmarks.physics.bands.correlations on 7 cm folds that grow over 6 frames. The
    cloth's fall to half their height from the top row to the bottom one; ours stand
    evenly. Ours is then a linear function of its frame means, so its correlation with
    the cloth's field equals that of the cloth's field's own frame means, sqrt(between-frame
    sum of squares / total): the analysis of variance, computed here without the module.
    The cloth's mean per row restores its field, and ours smoothed across changes nothing."""
    from benchmarks.physics.bands import correlations
    from benchmarks.physics.oracle import zones

    shot = flat_shot(rows=49, cols=65)
    shot.frames = 6
    shot.phases = {"push": (1, 6)}
    x, y = shot.material[:, 0], shot.material[:, 1]
    shot.pinned[y == 0.0] = True                # the rings
    wave = np.cos(2 * np.pi / 0.07 * x)
    grow = np.linspace(0.2, 1.0, shot.frames)[:, None]
    sim_h = 0.01 * grow * (1.0 - 0.5 * y / y.max()) * wave
    our_h = 0.008 * grow * wave
    parts = correlations(shot, sim_h, our_h)

    inner = zones(shot)["all"]
    field = measure.amplitude_field(shot, sim_h)[:, inner]
    between = (field.mean(1, keepdims=True) - field.mean()) ** 2 * field.shape[1]
    expected = np.sqrt(between.sum() / ((field - field.mean()) ** 2).sum())
    assert expected < 0.99                      # the place carries part of the field
    assert parts["whole"] == pytest.approx(expected, abs=2e-3)
    assert parts["frame means"] == pytest.approx(expected, abs=2e-3)
    assert parts["our rows"] == pytest.approx(expected, abs=2e-3)
    assert parts["ours smoothed across"] == pytest.approx(expected, abs=2e-3)
    assert parts["cloth rows"] > 0.999


@pytest.mark.parametrize("exact", [True, False])
def test_folds_are_scaled_to_draw_the_rest_area_around_them(exact):
    """benchmarks.physics.localarea.length_scaled on a sheet pushed to 0.5 of its width
    whose folds (z = a cos(2 pi x / 10 cm) along the pushed x) draw 1.2 times its rest
    area on the left and 0.9 times on the right (the length of the fold as the grid
    samples it, its chords over a wavelength, computed here by bisection). Scaled exactly,
    both sides draw their rest area: the scale is the amplitude at which the fold
    restores 2x its posed length over each side's own; scaled down, the right side keeps
    its folds. Away from the border (three windows), one frame."""
    from benchmarks.physics.localarea import length_scaled

    shot = flat_shot(rows=49, cols=129, spacing=0.01)
    x = shot.rest[:, 0]
    posed = shot.rest * [0.5, 1.0, 1.0]
    k = 2 * np.pi / 0.1

    def length(amplitude):  # per posed length, of the fold as the grid samples it
        step = 0.5 * shot.spacing
        at = np.arange(21) * step  # one wavelength, 20 grid cells
        return np.mean(np.hypot(step, np.diff(amplitude * np.cos(k * at)))) / step

    def amplitude_for(ratio):  # the amplitude whose fold draws ratio x its posed length
        lo, hi = 0.0, 1.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if length(mid) < ratio else (lo, mid)
        return lo

    left = x < 0.64
    amplitude = np.where(left, amplitude_for(2 * 1.2), amplitude_for(2 * 0.9))
    points = posed + np.stack([0 * x, amplitude * np.cos(k * posed[:, 0]), 0 * x], 1)
    scale = length_scaled(shot, posed[None], posed[None], points[None], exact, 0.02)[0]
    away = (np.abs(x - 0.64) > 3 * shot.window) & (x > 3 * shot.window) & (
        x < x.max() - 3 * shot.window)
    assert away[left].sum() > 0 and away[~left].sum() > 0
    if exact:
        expected = amplitude_for(2.0) / amplitude
    else:
        expected = np.where(left, amplitude_for(2.0) / amplitude, 1.0)
    # the Gaussian (5 cm of rest length) leaves a ripple of 0.4% along the 20 cm wave in
    # the area around each point, and the scale follows it
    np.testing.assert_allclose(scale[away], expected[away], rtol=6e-3)


def test_a_candidate_s_fallbacks_reach_what_reads_them_and_are_restored():
    """benchmarks.physics.candidate sets a candidate's fallbacks in-process: the width a
    cotton stage falls back to, the slack and irregularity a mesh without them reads, and
    the coarsening gate as folds.coarsening_cap applies it (W at 0.666 of its tube's, the
    25 cm sleeve's at cotton 8.1 cm: open with the window at (0.68, 0.8), closed at
    (0.56, 0.66)); all restored afterwards. And its bars are referee.BARS."""
    from benchmarks.physics.candidate import failures, fallbacks
    from usdwrinkle.method.folds import coarsening_cap
    from usdwrinkle.scene.params import curved_width
    from usdwrinkle.usd import schema

    before = (schema.DEFAULT_SLACK, schema.DEFAULT_IRREGULARITY, dict(schema.CLOTH_WIDTHS_M),
              schema.CURVED_WIDTH_M, float(coarsening_cap(0.666, 1.0)))
    assert before[-1] == pytest.approx(1.5)
    settings = {"slack": 0.04, "irregularity": 0.3, "widths": {"cotton": 0.081},
                "tube": 0.065, "gate": (0.56, 0.66)}
    with fallbacks(settings):
        assert (schema.DEFAULT_SLACK, schema.DEFAULT_IRREGULARITY) == (0.04, 0.3)
        assert float(curved_width(schema.CLOTH_WIDTHS_M["cotton"], np.array([0.0]))[0]) \
            == pytest.approx(0.081)
        assert float(curved_width(1.0, np.array([10.0]))[0]) == pytest.approx(0.065)
        assert float(coarsening_cap(0.666, 1.0)) == pytest.approx(1.0)
    assert (schema.DEFAULT_SLACK, schema.DEFAULT_IRREGULARITY, dict(schema.CLOTH_WIDTHS_M),
            schema.CURVED_WIDTH_M, float(coarsening_cap(0.666, 1.0))) == before
    row = {"wavelength": [0.97, 1.21], "heights": [0.86, 1.28], "correlation": 0.76,
           "motion": {"bend": 1.56, "held": 1.87}, "area": 1.017, "shear": True}
    assert failures(row) == ["height", "motion"]
    assert failures({**row, "shear": False}) == ["height", "correlation", "motion"]


def test_a_candidate_s_profile_fold_k_is_the_fold_preset_at_its_rounding():
    """benchmarks.physics.candidate's --profile foldK authors the fold with rounding K
    (fit.profile_values): at the preset's own K it is the default profile a stage that
    authors none draws, so the candidate's rows for it are the code's; the triangle is K = 1
    (the zigzag, 1 - 2|theta|/pi), and any other K rounds its crests below the triangle's."""
    from benchmarks.physics.candidate import candidate_text
    from benchmarks.physics.fit import profile_values
    from usdwrinkle.method.profiles import FOLD_ROUNDING, default_profile, profile_preset

    np.testing.assert_allclose(np.float32(profile_values(f"fold{FOLD_ROUNDING}")),
                               default_profile(), atol=1e-7)
    np.testing.assert_allclose(profile_values("fold1"), profile_preset("triangle"), atol=1e-6)
    theta = np.arange(len(default_profile())) * 2 * np.pi / len(default_profile())
    from_crest = np.abs(np.angle(np.exp(1j * theta)))
    near_crest = (from_crest > 0) & (from_crest < 0.3)  # the crest itself is 1 in both
    for k in (0.9, 0.97, 0.99):
        values = np.asarray(profile_values(f"fold{k}"))
        assert values.max() == pytest.approx(1.0) and values.min() == pytest.approx(-1.0)
        assert np.all(values[near_crest] > np.asarray(profile_preset("triangle"))[near_crest])
    assert candidate_text({"profile": "fold0.99", "slack": 0.04}) == \
        "the profile fold0.99 authored, slack 0.04"
    from benchmarks.physics.candidate import main
    for wrong in ("bogus", "foldx"):  # refused before any shot is baked
        with pytest.raises(SystemExit) as refused:
            main(["--profile", wrong, "--only", "curtain-silk"])
        assert refused.value.code == 2


def test_a_candidate_s_worst_case_is_the_farthest_any_shot_sits_from_a_bar():
    """benchmarks.physics.candidate's "worst": per bar the factor by which a row misses it
    (over 1) or comes near it (under 1), either way of a ratio, and the largest over the
    rows (issue 55 chooses the laws by the worst case over the sweep)."""
    from benchmarks.physics.candidate import excesses, worst

    leather = {"wavelength": [0.85, 1.01], "heights": [0.74, 1.25], "correlation": 0.835,
               "motion": {}, "area": 1.007, "shear": False}
    sleeve = {"wavelength": [0.92], "heights": [1.34], "correlation": 0.953,
              "motion": {"bend": 0.49, "held": 1.22}, "area": 0.948, "shear": False}
    e = excesses(leather)
    assert e["wavelength"] == pytest.approx(1 / 0.85 / 1.3)
    assert e["height"] == pytest.approx(1 / 0.74 / 1.25)  # the onset, not the 1.25x
    assert e["correlation"] == pytest.approx(0.85 / 0.835)
    assert e["area"] == pytest.approx(1.007 / 1.05)  # nearer the top of [0.95, 1.05]
    assert "motion" not in e
    s = excesses(sleeve)
    assert s["motion"] == pytest.approx(1.22 / 1.5)
    assert s["area"] == pytest.approx(0.95 / 0.948)
    assert worst({"curtain-leather": leather, "sleeve25-cotton": sleeve}) == \
        pytest.approx((1 / 0.74 / 1.25, "curtain-leather", "height"))
