"""The converging referee's shots (benchmarks/physics/sweep.py, elbow.py), without running
a simulator: the same cloth at every grid spacing, and the shirt's sleeve riding on the
shirt's joints as UsdSkel poses them."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Usd, UsdSkel

from benchmarks.physics import elbow
from benchmarks.physics.sweep import FABRICS, curtain, shear, sleeve, spec

SHIRT = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"


@pytest.mark.parametrize("make", [curtain, shear, lambda f, h: sleeve(f, h, 0.10)])
def test_a_sweep_shot_is_the_same_cloth_at_half_the_spacing(make):
    """Halving the grid keeps the cloth: its material extent, its pins' material places
    (the curtain's rings every 6 cm), its keyed motion and its bending in N m."""
    coarse, fine = make("cotton", 0.01), make("cotton", 0.005)
    assert fine.shot.spacing == pytest.approx(coarse.shot.spacing / 2, rel=0.02)
    a, b = coarse.shot, fine.shot
    np.testing.assert_allclose(np.ptp(a.material, 0), np.ptp(b.material, 0), rtol=0.02)
    # every coarse pin has a fine pin at its material place
    pa, pb = a.material[a.pinned], b.material[b.pinned]
    near = np.min(np.linalg.norm(pa[:, None] - pb[None], axis=2), axis=1)
    assert near.max() < 0.5 * a.spacing
    assert [f for f, _ in a.keys] == [f for f, _ in b.keys]
    assert spec(fine)["bending"] == FABRICS["cotton"]


@pytest.mark.parametrize("spacing", [0.02, 0.01, 0.005])
def test_the_curtain_s_rings_are_6_cm_apart_and_a_sleeve_s_rings_double(spacing):
    """The curtain hangs from rings every 6 cm along its rail at every grid (a constant of
    the sleeve's once shadowed this one and pinned every 2 cm, which changed the curtain's
    arrays and so its cache names); a sleeve's points around double with each halving of
    the spacing, which sweep.resample needs (the 25 cm sleeve had 312 at 0.5 cm, not 320)."""
    from benchmarks.physics.sweep import resample

    shot = curtain("cotton", spacing).shot
    top = shot.pinned.reshape(shot.rows, shot.cols)[0]
    below = shot.pinned.reshape(shot.rows, shot.cols)[1]
    rings = np.sort(shot.material[:shot.cols][top & ~below][:, 0])
    np.testing.assert_allclose(np.diff(rings), 0.06, atol=0.5 * shot.spacing)
    for radius in (0.05, 0.10, 0.25):
        coarse, fine = sleeve("cotton", 2 * spacing, radius), sleeve("cotton", spacing, radius)
        assert fine.shot.cols == 2 * coarse.shot.cols
        points = coarse.shot.rest[None]
        assert resample(points, coarse, fine).shape == (1, fine.shot.rows * fine.shot.cols, 3)


@pytest.mark.parametrize("radius, zone", [(0.05, 0.20), (0.10, 0.20), (0.25, 0.50)])
def test_a_bent_sleeve_s_arm_does_not_pass_through_itself(radius, zone):
    """The sweep's sleeves bend 90 degrees over 20 cm, over twice the radius beyond 10 cm
    (sweep.elbow_length): at the full bend the arm's axis curves at the radius zone / (pi
    / 2) (a circle through three axis points in the elbow, by hand), over the arm's own
    0.8 R; 1.27 R on the 10 and 25 cm sleeves (at 20 cm the 25 cm sleeve's arm, 20 cm
    thick, would fold into itself on an axis of radius 12.7 cm)."""
    from benchmarks.physics.sweep import elbow_length

    assert elbow_length(radius) == pytest.approx(zone)
    shot = sleeve("cotton", 0.02, radius)
    ends = [np.asarray(capsule[0]) for capsule in shot.capsules[-1]] + \
        [np.asarray(shot.capsules[-1][-1][1])]
    a, b, c = ends[3], ends[6], ends[9]  # inside the elbow's eleven points
    # the circumradius of the triangle a b c
    ab, bc, ca = (np.linalg.norm(u - v) for u, v in ((a, b), (b, c), (c, a)))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a))
    bent = ab * bc * ca / (4 * area)
    assert bent == pytest.approx(zone / (np.pi / 2), rel=1e-6)
    assert bent > shot.capsules[-1][0][2] == pytest.approx(0.8 * radius)


def _ring_centres(points: np.ndarray, x: np.ndarray, at: float) -> np.ndarray:
    ring = np.abs(x - at) < 1e-6
    return points[ring].mean(axis=0)


@pytest.mark.parametrize("frame", [12, 24])
def test_the_simulated_sleeve_rides_on_the_shirt_s_joints(frame):
    """The fine sleeve's pinned end rings, keyed for the simulation, sit where UsdSkel
    skins the coarse shirt's end rings (ComputeSkinnedPoints), centre and radius, in the
    simulation's metres."""
    sweep_shot, sim_frame = elbow.shirt_sleeve(shirt_frames=range(1, 25))
    shot = sweep_shot.shot
    keyed = dict(shot.keys)[sim_frame[frame]]
    stage = Usd.Stage.Open(str(SHIRT))
    cache = UsdSkel.Cache()
    root = UsdSkel.Root(stage.GetPrimAtPath("/World/Arm"))
    cache.Populate(root, Usd.TraverseInstanceProxies())
    skel_query = cache.GetSkelQuery(UsdSkel.Skeleton(stage.GetPrimAtPath(elbow.SKELETON)))
    skinning = cache.GetSkinningQuery(stage.GetPrimAtPath(elbow.SLEEVE))
    mesh = stage.GetPrimAtPath(elbow.SLEEVE)
    rest = np.asarray(mesh.GetAttribute("points").Get(), np.float64)
    points = mesh.GetAttribute("points").Get()
    skinning.ComputeSkinnedPoints(skel_query.ComputeSkinningTransforms(frame), points, frame)
    posed = np.asarray(points, np.float64)
    fine_rest_x = elbow.from_sim(shot.rest)[:, 0]
    for end in (0.0, elbow.LENGTH):
        ours = elbow.from_sim(_ring_centres(keyed, fine_rest_x, end))
        theirs = _ring_centres(posed, rest[:, 0], end)
        np.testing.assert_allclose(ours, theirs, atol=0.01 * elbow.RADIUS)
        ring = np.abs(fine_rest_x - end) < 1e-6
        radius = np.linalg.norm(elbow.from_sim(keyed[ring]) - ours, axis=1)
        coarse = np.linalg.norm(posed[np.abs(rest[:, 0] - end) < 1e-6] - theirs, axis=1)
        assert np.median(radius) == pytest.approx(np.median(coarse), rel=0.01)


def test_the_converged_table_keeps_the_rows_of_shots_not_simulated_here(tmp_path, monkeypatch):
    """referee --keep-uncached: a shot whose simulation is not in the cache keeps its row
    and its phase-by-phase line from the block being replaced, marked as kept (once, however
    often the block is made again), instead of being simulated for hours; a shot with no
    row to keep is refused. The repository's kept simulations are hidden (a checkout
    without them: since 2026-12-08 all ten are kept)."""
    from benchmarks.blocks import markers
    from benchmarks.physics import kept as kept_simulations
    from benchmarks.physics import referee

    monkeypatch.setattr(kept_simulations, "KEPT", tmp_path / "no-kept-simulations")

    begin, end = markers(referee.TABLES["converged"])
    row = "| curtain-silk | 2.5e-06 | 1 cm | 5.0 cm | 7.2, 7.6 cm | 1.15x | 1.30x | 0.95 | - |"
    phases = "- curtain-silk: push to 8% 1.15, 0.75; held at 48% 0.90, 1.23"
    doc = f"text\n{begin}\n\n| shot | D |\n|---|---|\n{row}\n\n{phases}\n\n{end}\nmore\n"
    assert referee.kept_rows(doc, "converged", "curtain-silk") == (row, phases)
    assert referee.kept_rows(doc, "converged", "curtain-cotton") is None
    empty = tmp_path / "cache"
    text = referee.sweep_report(["curtain-silk"], empty, "converged", keep=doc)
    assert text.startswith(begin) and text.endswith(end)
    kept = row.replace("| curtain-silk |", "| curtain-silk *kept* |")
    assert kept in text.splitlines() and phases in text.splitlines()
    assert "--keep-uncached" in text and "kept from the table before" in text
    again = referee.sweep_report(["curtain-silk"], empty, "converged", keep=text)
    assert kept in again.splitlines() and "*kept* *kept*" not in again
    with pytest.raises(SystemExit, match="curtain-cotton is not simulated"):
        referee.sweep_report(["curtain-cotton"], empty, "converged", keep=doc)


@pytest.mark.parametrize("profile", ["fold0.9", "fold", "box"])
def test_the_area_is_taken_on_a_grid_as_fine_as_the_bake_samples_the_profile(profile):
    """referee.area_grid samples W as usdwrinkle's geometry bake does, the height profile's
    factor included (a sharper crest gets more points a wavelength than the fold at
    K = 0.9 the samples were measured on: the default fold, K = 0.97, 1.79x; box 2x), so
    that a sharper profile's area is not the grid's loss (docs/physics.md, "The fold's
    rounding, probed": the 10 cm silk sleeve 0.969 -> 0.962 at K = 0.97 on the grid of
    the fold at K = 0.9)."""
    from pxr import Sdf

    from benchmarks.physics import referee
    from benchmarks.physics.fit import profile_values
    from usdwrinkle.geometry.options import DEFAULT_SAMPLES_PER_WAVELENGTH
    from usdwrinkle.usd import schema

    values = profile_values(profile)
    factor = referee.profile_factor_of(
        {schema.HEIGHT_PROFILE: (Sdf.ValueTypeNames.FloatArray, values)})
    expected = {"fold0.9": 1.0, "fold": 1.790, "box": 2.0}[profile]
    assert factor == pytest.approx(expected, abs=1e-3)
    # the default profile is the fold (K = 0.97 since 2026-12-08)
    assert referee.profile_factor_of(None) == pytest.approx(1.790, abs=1e-3)
    for width in (0.049, 0.077, 0.095, 0.122):  # the sweep's matched widths, flat cloth
        grid = referee.area_grid(width, None, factor)
        assert grid <= width / (DEFAULT_SAMPLES_PER_WAVELENGTH * factor)
        assert grid * 2 > width / (DEFAULT_SAMPLES_PER_WAVELENGTH * factor) or \
            grid == referee.SPACING


def test_one_shot_is_simulated_by_one_process_at_a_time(tmp_path):
    """simulate.py's lock (fill.py runs several simulations at once): a second process
    asking for the same shot is refused while the first holds it, and a lock whose
    process is gone (a run killed with the session) is taken over."""
    import os
    import subprocess
    import sys

    from benchmarks.physics.simulate import _simulating

    out = tmp_path / "newton-shot.npz"
    lock = tmp_path / "newton-shot.npz.lock"
    with _simulating(out):
        assert lock.read_text() == str(os.getpid())
        with pytest.raises(RuntimeError, match="being simulated by process"):
            with _simulating(out):
                pass
    assert not lock.exists()
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    lock.write_text(gone)
    with _simulating(out):
        assert lock.read_text() == str(os.getpid())


def test_the_cache_is_filled_longest_first():
    """fill.py's order: the 1 cm curtains (6,305 points, 100 frames) before the sheared
    panels and the sleeves, so that several at once end together."""
    from benchmarks.physics import fill, referee

    order = fill.planned("converged", None)
    assert order[:3] == ["curtain-silk", "curtain-cotton", "curtain-leather"]
    assert set(order) == set(referee.SWEEP)
    assert order[-1].startswith("sleeve10")
    assert "sleeve25-cotton" not in fill.planned("sweep", None)


def test_a_kept_simulation_is_read_instead_of_simulated(tmp_path, monkeypatch):
    """kept.py: a simulation kept in the repository comes back within half its step
    (int16 steps from the frame before, as kept, so that the rounding does not add up
    over the frames), and simulate_newton reads it into an empty cache instead of
    running Newton (which this test has none of). On the converged 25 cm sleeve the
    step is 0.8 micrometres, and its referee row is the cache's to the last digit."""
    from benchmarks.physics import kept, simulate
    from benchmarks.physics.sweep import curtain

    monkeypatch.setattr(kept, "KEPT", tmp_path / "kept")
    monkeypatch.setenv("USDWRINKLE_NEWTON_PYTHON", str(tmp_path / "no-newton"))
    shot = curtain("cotton", 0.04)
    source = tmp_path / "source"
    cached, _ = simulate.newton_path(shot, source)
    rng = np.random.default_rng(3)
    rest = shot.shot.rest.astype(np.float32)
    # 40 frames that push it up to 48 cm, as the curtains are pushed, with a shake
    push = rng.uniform(-0.012, 0.012, rest.shape)
    points = np.stack([rest + k * push + rng.normal(0, 0.001, rest.shape)
                       for k in range(40)]).astype(np.float32)
    source.mkdir()
    np.savez(cached, points=points, seconds=12.5, stretch_p99=0.004)
    out = kept.keep(cached)
    assert out.parent == tmp_path / "kept"

    cache = tmp_path / "cache"
    assert simulate.cached_newton(shot, cache)  # kept counts as cached
    back, seconds, stretch = simulate.simulate_newton(shot, cache)
    step = float(np.load(out)["scale"])
    assert 0 < step < 1e-6
    assert np.array_equal(back[0], points[0])
    assert np.abs(back.astype(np.float64) - points).max() <= 0.5 * step + 1e-6
    assert (seconds, stretch) == (12.5, 0.004)
    assert simulate.newton_path(shot, cache)[0].exists()  # now in the cache too
