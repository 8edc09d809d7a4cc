"""Stable crests (issue 46): a tiny change of the input moves the crests a little, not to
other places; a local change stays local.

The cause, measured (docs/method.md, "Stability"): a point without a wave (amplitude 0)
carried last frame's phase through the flip test k_prev . k < 0, whose k there means
nothing, so rounding chose the sign; a wrinkle that grew there later inherited it. With 0
relax iterations the shirt moved as much (23-25% of wrinkled pixels at 0.01 degrees) as
with 8, so the relaxation was not the cause. Such points now start each frame from their
material-anchored phase. The measurements are benchmarks/stability.py's.
"""
from __future__ import annotations

import numpy as np
import pytest

from benchmarks import stability
from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.reference.relax import relax_frame, ring_edges, seed, wrap

from helpers import point_cache_stage, random_cloth


def test_a_tiny_joint_change_moves_no_crest_on_the_shirt(gl_context, tmp_path):
    """Before: 24-31% of wrinkled pixels at 0.01 degrees, 18-31% at 0.1."""
    shares = stability.perturbation(str(stability.SHIRT), str(tmp_path), ctx=gl_context)
    assert all(shares[0.01][f] <= 0.02 for f in stability.FRAMES), shares
    assert all(shares[0.1][f] <= 0.05 for f in stability.FRAMES), shares


def test_a_tiny_joint_change_moves_no_crest_of_a_loop_painted_around_the_arm(gl_context,
                                                                            tmp_path):
    """q painted around the forearm: the phase must wind around the arm. Before the painted
    waves started from their stripe pattern (method/anchor.py), they started with no winding
    and the relaxation's dislocations went where rounding put them: 1.8, 2.5, 2.0, 0.4 and
    0.3% of the wrinkled pixels moved at 0.01 degrees (frames 8-24)."""
    layer = stability.painted_loop(str(tmp_path))
    shares = stability.perturbation(layer, str(tmp_path), ctx=gl_context)
    assert all(shares[0.01][f] <= 0.02 for f in stability.FRAMES), shares
    assert all(shares[0.1][f] <= 0.05 for f in stability.FRAMES), shares


@pytest.mark.parametrize("axis", stability.OTHER_AXES)
@pytest.mark.parametrize("stage", ["shirt", "loop"])
def test_a_tiny_joint_change_about_another_axis_moves_no_crest(gl_context, tmp_path, stage,
                                                               axis):
    """One axis is one draw of where rounding lands. Before 2026-12-04 (relax: a new wave
    took the phase that the floor weights had made of its neighbours' even beside kept
    waves, a neighbour at right angles pulled with a coin toss's sign, and a neighbour
    without a wave turned the mobility; docs/method.md, "Three couplings"), 0.01 degrees
    about x moved 7.4-18.8% of the shirt's wrinkled pixels at frames 12-24 on llvmpipe
    (about z 0.2%), and an H200 moved 2.2% of them about z. Until the crest damping's
    gate and the bare points' alignment (the same evening), the painted loop about x moved
    2.4% at frame 16 on llvmpipe."""
    path = str(stability.SHIRT) if stage == "shirt" else stability.painted_loop(str(tmp_path))
    shares = stability.perturbation(path, str(tmp_path), degrees=(0.01,), ctx=gl_context,
                                     axis=axis)[0.01]
    assert all(shares[f] <= 0.02 for f in stability.FRAMES), shares


#: the random axis (benchmarks.stability.random_axes(64)) about which 0.01 degrees moved
#: the most of the shirt's crests, 18.2% at frame 24, before crush's damping was gated by
#: the slack and a point without a wave was pulled only along its own direction
#: (2026-12-04; docs/method.md, "Three couplings"); over 64 axes the worst is 0.3% since
WORST_SHIRT_AXIS = 36


def test_a_tiny_joint_change_about_the_worst_random_axis_moves_no_crest(gl_context,
                                                                       tmp_path):
    """The shirt's elbow grew its first waves at frame 4 along directions 2 degrees apart
    between the two runs: the crest damping had carried the direction of the frames
    before, when the strain there compressed nothing and had no direction of its own.
    Their phases then relaxed 0.3-0.6 rad apart, and the region's crests with them."""
    axis = stability.random_axes(64)[WORST_SHIRT_AXIS]
    shares = stability.perturbation(str(stability.SHIRT), str(tmp_path), degrees=(0.01,),
                                     ctx=gl_context, axis=axis)[0.01]
    assert all(shares[f] <= 0.02 for f in stability.FRAMES), shares


@pytest.mark.parametrize("stage", ["shirt", "loop"])
def test_a_small_joint_change_about_random_axes_moves_few_crests(gl_context, tmp_path,
                                                                 stage):
    """0.1 degrees about each of 8 random axes (benchmarks.stability.random_axes), bar 5%:
    the worst case over draws, not one draw. Before the damping's gate and the bare points'
    alignment (2026-12-04), 12 of 32 such axes moved more than 5% of the shirt's crests
    (up to 18.4%) and 5 of 32 the loop's (up to 9.2%); among these 8, the shirt's moved
    6.3% and 18.4%, the loop's 5.5% and 7.0%."""
    path = str(stability.SHIRT) if stage == "shirt" else stability.painted_loop(str(tmp_path))
    base = stability.heights(path, ctx=gl_context)
    worst = {}
    for index, axis in enumerate(stability.random_axes(8)):
        shares = stability.perturbation(path, str(tmp_path), degrees=(0.1,), ctx=gl_context,
                                         axis=axis, base=base)[0.1]
        worst[index] = max(shares.values())
    assert max(worst.values()) <= 0.05, worst


@pytest.mark.parametrize("stage", ["shirt", "loop"])
def test_a_tiny_joint_change_moves_no_wave_s_phase_on_the_sleeve(gl_context, tmp_path,
                                                                 stage):
    """The phases themselves, not the image: 0.01 degrees about each of 4 random axes moves
    no wave of the sleeve's coarse points that the relaxation weighs by more than 0.5 rad at
    any of FRAMES (stability.moved_waves: the folds drawn before the crests settle, which
    take their phases from their neighbours', moved 2-3 of them, at most 22% of the largest
    fold; the images above count them; `python -m benchmarks.stability --draws 16
    --phases`). The image measure above did not see the shirt's elbow settle into one of two
    layouts of its phases: with the old rig (linear blending, the forearm's weight rising
    over 0.7 units around the elbow) up to 29 waves moved, a median of 7.5 over 16 draws,
    and 20 of the painted loop's; with the rig since 2026-12-04 (dual quaternions, the
    weight rising from 0.8 to 2.1) none in 16 draws (docs/method.md, "What the image does
    not see")."""
    path = str(stability.SHIRT) if stage == "shirt" else stability.painted_loop(str(tmp_path))
    base = stability.sleeve_fields(path, stability.FRAMES, gl_context)
    assert int((base[24]["weight"] > 0).sum()) > 50  # waves that could move
    moved = stability.moved_wave_counts(path, list(enumerate(stability.random_axes(4))),
                                        0.01, str(tmp_path), gl_context, base)
    assert all(count == 0 for _, count in moved), moved


def test_a_tiny_joint_change_moves_no_crest_on_cesium_man(gl_context, corpus, tmp_path):
    stage = stability.with_units(str(corpus / "usd-wg" / "CesiumMan.usdz"),
                                 str(tmp_path / "cesium.usda"))
    shares = stability.perturbation(stage, str(tmp_path), all_meshes=True, ctx=gl_context)
    assert all(shares[0.01][f] <= 0.02 for f in stability.FRAMES), shares
    assert all(shares[0.1][f] <= 0.05 for f in stability.FRAMES), shares
    assert max(shares[0.1].values()) > 0  # the perturbation reaches the meshes


#: the random axes (benchmarks.stability.random_axes(32)) about which 0.1 degrees moved
#: more than 5% of CesiumMan's crests at the fallback slack while the cold start's steps
#: were normalised: 6.4% and 5.9%
CESIUM_MAN_TIPPED = (8, 23)


def test_the_cold_start_does_not_tip_cesium_man_under_a_small_joint_change(gl_context,
                                                                          corpus, tmp_path):
    """Where the first frame's defects settle was a lottery a 0.1 degree change could tip
    (CesiumMan: 2 of 32 random axes over the 5% bar at the slack 0.05, 29 of 32 at 0.055);
    the cold start's steps are the weighted mean since 2026-12-07, and those two axes move
    0.13% and 0.37% (docs/method.md, "The cold start's steps are the weighted mean")."""
    stage = stability.with_units(str(corpus / "usd-wg" / "CesiumMan.usdz"),
                                 str(tmp_path / "cesium.usda"))
    base = stability.heights(stage, all_meshes=True, ctx=gl_context)
    axes = stability.random_axes(32)
    for index in CESIUM_MAN_TIPPED:
        shares = stability.perturbation(stage, str(tmp_path), all_meshes=True,
                                        degrees=(0.1,), ctx=gl_context, axis=axes[index],
                                        base=base)[0.1]
        assert max(shares.values()) > 0, index  # the change reaches the mesh
        assert max(shares.values()) <= 0.05, (index, shares)


def test_q_painted_on_the_cuff_changes_crests_only_near_it(gl_context, tmp_path):
    """Before: crests moved 6.25 W (7 edges) away, along the whole sleeve. The bar is 2 W
    or 2 edges, whichever is farther: the phases live on the points, and where W is
    shorter than the edges (the shirt's W = 0.1, its rings 0.25 apart: 1.79 W at W =
    0.28 and 5 W now are the same 2 rings) no change can stay closer than the next ring."""
    rows = stability.locality(str(tmp_path), ctx=gl_context)
    assert all(count > 0 for count, _, _ in rows.values())  # the painting changed the cuff
    assert all(far <= 2.0 or hops <= 2 for _, far, hops in rows.values()), rows


def test_a_zero_perturbation_changes_nothing(gl_context, tmp_path):
    base = stability.heights(str(stability.SHIRT), frames=(24,), ctx=gl_context)
    same = stability.heights(stability.perturbed(str(stability.SHIRT), 0.0,
                                                 str(tmp_path / "p0.usda")),
                             frames=(24,), ctx=gl_context)
    assert stability.moved_share(base, same) == {24: 0.0}
    assert np.array_equal(base[24][0], same[24][0])


def test_waves_that_grow_in_start_as_the_reference_does(gl_context):
    """A stretched cloth (no wave anywhere) is squashed over frames 2 and 3: the waves
    that grow in beside waves that were there start from the phase those ask for, the
    others from their last phase. reference/relax.py's relax_frame, fed the GPU's
    own crush output and previous state (the float64 crush places the crests of such a
    frame elsewhere, docs/method.md: sensitivity), gives the GPU's phases; the old seed
    does not."""
    rest, posed, faces, _ = random_cloth(5)
    q = np.zeros_like(rest)
    frames = {1: 1.3 * rest, 2: 0.5 * (1.3 * rest + posed), 3: posed}  # 1: stretched
    iterations = 6
    gpu, raw = {}, {}
    # crush's own waves: relax's fit rewrites k and the amplitude after relaxing, and a
    # shot without relaxation (0 iterations) has no fit; crush does not depend on relax
    for count, out in ((iterations, gpu), (0, raw)):
        stage = point_cache_stage(rest, {f: p.astype(np.float32) for f, p in frames.items()},
                                  np.full(len(faces), 3), faces.ravel(), q=q, width=0.2,
                                  relax_iterations=count)
        engine = WrinkleEngine(stage, ctx=gl_context)
        try:
            for frame in (1, 2, 3):
                engine.compute_frame(float(frame))
                out[frame] = engine.read_fields("/Sheet").arrays()
            topology = engine.meshes["/Sheet"].topology
        finally:
            engine.release()
    assert not np.any(gpu[1]["amplitude"] > 0)  # no wave on the stretched cloth
    for frame in (2, 3):
        before, now, crushed = gpu[frame - 1], gpu[frame], raw[frame]
        fields = {"points": crushed["points"], "wave_vector": crushed["wave_vector"],
                  "amplitude": crushed["amplitude"], "phase": crushed["anchor_phase"],
                  "normals": crushed["normals"]}
        state = {"wave_vector": before["wave_vector"], "phase": before["phase"],
                 "amplitude": before["amplitude"]}
        phase, _ = relax_frame(fields, state, topology, iterations)
        grown = (now["amplitude"] > 0) & ~(before["amplitude"] > 0)
        assert grown.sum() > 40
        # frame 3 grows waves beside the ones frame 2 grew: those start from the phase
        # their neighbours ask for (the seed's ring), the others from their last phase
        src, dst = ring_edges(topology)
        beside = np.zeros(len(grown), bool)
        beside[src[(now["amplitude"] > 0)[dst] & (before["amplitude"] > 0)[dst]]] = True
        assert (grown & beside).sum() == 0 if frame == 2 else (grown & beside).sum() > 20
        # float32 against float64: 1.2e-4 at one of 642 points since a point without a
        # wave is pulled only along its own direction (2026-12-04)
        np.testing.assert_allclose(wrap(now["phase"] - phase), 0.0, atol=2e-4)
        # the seed without the ring (history wherever there is a wave) is another frame
        # 3: the test can tell them apart
        old = seed(crushed["wave_vector"], before["wave_vector"], before["phase"],
                   crushed["amplitude"], crushed["anchor_phase"])
        ours = seed(crushed["wave_vector"], before["wave_vector"], before["phase"],
                    crushed["amplitude"], crushed["anchor_phase"], before["amplitude"],
                    crushed["points"], topology)
        apart = np.abs(wrap(old - ours))[grown & beside]
        assert apart.size == 0 if frame == 2 else apart.max() > 1.0


def test_the_seed_keeps_history_only_where_there_is_a_wave():
    k = np.array([[1.0, 0, 0], [1.0, 0, 0], [1.0, 0, 0]])
    previous_k = np.array([[1.0, 0, 0], [-1.0, 0, 0], [-1.0, 0, 0]])
    previous_phase = np.array([0.5, 0.5, 0.5])
    amplitude = np.array([0.1, 0.1, 0.0])
    anchor = np.array([2.0, 2.0, 2.0])
    start = seed(k, previous_k, previous_phase, amplitude, anchor)
    np.testing.assert_allclose(start, [0.5, -0.5, 2.0])  # kept, flipped, anchored
    np.testing.assert_allclose(seed(k, previous_k, previous_phase), [0.5, -0.5, -0.5])


def test_a_new_wave_starts_from_the_phase_its_kept_neighbours_ask_for():
    """A wave that was not there last frame does not keep the phase the relaxation's floor
    weights made for its point where waves that were there are beside it: it starts from
    the phase they ask for (their pulls, along k_bar . (x_j - x_i)); with none beside it,
    from its last phase. On a flat grid whose history runs 0.3 rad ahead of the anchored
    plane wave, a new wave at the centre whose last phase lags 1 rad behind starts 0.3
    rad ahead."""
    from usdwrinkle.authoring.builders import grid_sheet
    from usdwrinkle.scene.topology import build_topology

    points, counts, indices = grid_sheet(9, 9, 2.0)
    points = np.asarray(points, np.float64)
    topology = build_topology(counts, indices, points)
    n = len(points)
    centre = int(np.argmin(np.linalg.norm(points, axis=1)))
    k = np.tile([3.0, 0.0, 0.0], (n, 1))
    anchor = 3.0 * points[:, 0]
    history = wrap(anchor + 0.3)
    history[centre] = wrap(anchor[centre] - 1.0)  # its floor-relaxed phase
    amplitude = np.full(n, 0.01)
    before = amplitude.copy()
    before[centre] = 0.0  # new at the centre
    start = seed(k, k, history, amplitude, anchor, before, points, topology)
    assert wrap(start[centre] - anchor[centre]) == pytest.approx(0.3, abs=1e-9)
    np.testing.assert_allclose(wrap(start - history)[np.arange(n) != centre], 0.0, atol=1e-12)
    # without the ring (or with no kept wave beside it): its last phase
    assert seed(k, k, history, amplitude, anchor, before)[centre] == history[centre]
    alone = seed(k, k, history, amplitude, anchor, np.zeros(n), points, topology)
    np.testing.assert_allclose(alone, history)


@pytest.mark.parametrize("name", ["shirt", "zeppelin", "curtain"])
def test_crests_still_ride_with_the_cloth(gl_context, name):
    """The history is kept where there is a wave: the swim stays what it was (0.33, 0.014,
    0.12 rad per frame before; test_history.py holds the bars)."""
    from usdwrinkle.reference.relax import phase_swim

    engine = WrinkleEngine(str(stability.ROOT / "sample_stages" / f"{name}.usda"),
                           ctx=gl_context)
    path = engine.wrinkled_paths[0]
    swims, previous = [], None
    try:
        for frame in range(1, 25):
            engine.compute_frame(float(frame))
            current = engine.read_fields(path).arrays()
            if frame >= 10:
                swims.append(phase_swim(previous, current))
            previous = current
    finally:
        engine.release()
    # the zeppelin's deflating hull coarsens its folds all along the shot, and its crests
    # move with them (0.014 before the fold law, 0.16 with it and the area across; docs/method.md)
    assert np.mean(swims) <= {"shirt": 0.34, "zeppelin": 0.17, "curtain": 0.13}[name], swims


#: the mean misfit over the stage and its 15 joint changes before the stability change
#: (commit f822306; docs/method.md: "What the change costs", benchmarks/misfit.py). The
#: shirt's measured again with f822306's src when its W went from 0.28 to 0.1 (0.365 at
#: 0.28): finer waves on the same coarse mesh align worse, before and now
MISFIT_BEFORE = {"shirt": 0.577, "zeppelin": 0.388, "curtain": 0.562}
#: the fold law's (issue 55): the zeppelin's material wavelength varies over the hull as
#: its compression does, and no phase field follows that curl (0.67; docs/method.md)
MISFIT_BOUND = {**MISFIT_BEFORE, "zeppelin": 0.68}


@pytest.mark.parametrize("name", ["shirt", "zeppelin", "curtain"])
def test_neighbouring_waves_align_no_worse_than_before(gl_context, tmp_path, name):
    """The misfit, a distribution where rounding places the dislocations (the curtain's
    0.456 before the change was its luckiest of 16 draws), is no worse in the mean: 0.368,
    0.376, 0.549 now; the shirt at W = 0.1 0.454 now, 0.577 before."""
    from benchmarks import misfit

    path = stability.ROOT / "sample_stages" / f"{name}.usda"
    draws = [misfit.run_stage(str(path) if deg == 0 else
                              stability.perturbed(str(path), deg, str(tmp_path / f"{deg}.usda")),
                              gl_context)[0] for deg in misfit.DEGREES]
    assert len(set(draws)) > 1  # the joint changes reach the phases
    assert np.mean(draws) <= MISFIT_BOUND[name] + 0.005, draws


def test_draws_take_the_slack_they_are_given_and_give_the_code_s_back(monkeypatch,
                                                                       gl_context):
    """`python -m benchmarks.stability --draws N --slack C` (docs/physics.md, "The slack
    and the crests' stability"): each worker draws with the wrinkle:slack fallback C, which
    reaches the frames (the shirt authors none), and gives the code's back after."""
    from usdwrinkle.usd import schema

    seen = []

    def stage_draws(stage, degrees, axes, phases):
        seen.append(schema.DEFAULT_SLACK)
        _, amplitude, alpha = stability.heights(str(stability.SHIRT), frames=(12,),
                                                ctx=gl_context)[12]
        covered = alpha > 0.5
        return stage, [(0, float((amplitude[covered] > 0).mean()))]

    monkeypatch.setattr(stability, "_stage_draws", stage_draws)
    code = schema.DEFAULT_SLACK
    _, [(_, loose)] = stability._draws_of(("shirt", 0.01, [], False, 0.3))
    _, [(_, default)] = stability._draws_of(("shirt", 0.01, [], False, None))
    assert seen == [0.3, code] and schema.DEFAULT_SLACK == code
    # folds begin at 30% compression instead of the fallback's: the unpainted sleeve
    # keeps far fewer of them at frame 12
    assert loose < 0.8 * default, (loose, default)
