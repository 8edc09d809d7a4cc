"""The wave blend (include/wave.glsl, blend_corner_waves) number by number against its numpy
reference (usdwrinkle/reference/blend.py): the paper's barycentric blend of the corner
waves, divided by its coherence (docs/method.md, "Coherence"), with its exact gradient. The
draw pass, the maps and the displaced geometry all call this one function
(tests/test_contract.py checks that it is written once)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from usdwrinkle.method.contract import BLEND_COHERENCE_FLOOR
from usdwrinkle.method.profiles import default_profile, derive_gradient
from usdwrinkle.reference.blend import blend_at, weight_gradients
from usdwrinkle.render.bindings import COMMON, WAVE
from usdwrinkle.render.shaders import compute_shader

SHADERS = Path(__file__).resolve().parent / "shaders"
COUNT = 400


def cases(seed: int, agree: bool):
    """COUNT triangles in the xy plane with corner waves running within 40 degrees of
    each other (sign-aligned, as corner_waves aligns them), 0.2-1.5 units long. With
    ``agree`` the three corners share one wave and phase field (theta the same at every
    point): the paper's blend, which the coherence must leave as it is."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(COUNT):
        corners = np.zeros((3, 3))
        corners[:, :2] = rng.uniform(-0.6, 0.6, (3, 2))
        if abs(np.cross(corners[1] - corners[0], corners[2] - corners[0])[2]) < 0.1:
            corners[2, :2] += 0.6
        base = rng.uniform(0, 2 * np.pi)
        angles = base + (0.0 if agree else rng.uniform(-0.7, 0.7, 3))
        lengths = np.full(3, rng.uniform(0.2, 1.5)) if agree else rng.uniform(0.2, 1.5, 3)
        k = np.zeros((3, 3))
        k[:, 0], k[:, 1] = np.cos(angles), np.sin(angles)
        k *= (2 * np.pi / lengths)[:, None]
        a = rng.uniform(0.05, 0.2, 3)
        if not agree and rng.uniform() < 0.1:
            a[rng.integers(3)] = 0.0  # a corner with no wave
        if agree:
            phases = rng.uniform(0, 2 * np.pi) + (corners - corners[0]) @ k[0]
        else:
            phases = rng.uniform(0, 2 * np.pi, 3)
        bary = rng.dirichlet(np.ones(3))
        out.append((np.concatenate([k, a[:, None]], 1), phases, corners, bary,
                    bary @ corners))
    return out


@pytest.fixture(scope="module")
def blend(gl_context):
    """Runs blend_corner_waves on the GPU for a list of cases: (exact h, exact gradient,
    tangent-plane gradient) per case."""
    ctx = gl_context
    height = default_profile().astype(np.float32)
    gradient = derive_gradient(height).astype(np.float32)
    textures = []
    for unit, table in ((WAVE["WAVE_HEIGHT_PROFILE"], height),
                        (WAVE["WAVE_GRADIENT_PROFILE"], gradient)):
        texture = ctx.texture((len(table), 1), 1, table.tobytes(), dtype="f4")
        texture.repeat_x, texture.repeat_y = True, False
        texture.use(location=unit)
        textures.append(texture)
    shader = compute_shader(ctx, "blend_probe.glsl", {**COMMON, **WAVE}, root=SHADERS)
    shader["u_profile_samples"] = float(len(height))
    rough = compute_shader(ctx, "blend_probe.glsl", {**COMMON, **WAVE, "IRREGULAR": 1},
                           root=SHADERS)
    rough["u_profile_samples"] = float(len(height))

    def run(items, irregular=None, deepen=None):
        """``irregular``: (the rest corners per case, their rest directions per case,
        beta, 1 / Lambda), run on the IRREGULAR variant; ``deepen``: each case's three
        corners' (offset, gradient) (FIELD_DEEPEN; zero by default)."""
        program = shader
        data = np.zeros((len(items), 18, 4), np.float32)
        if deepen is not None:
            data[:, 15:18] = deepen
        for i, (waves, phases, corners, bary, p) in enumerate(items):
            data[i, :3] = waves
            data[i, 3, :3] = phases
            data[i, 4:7, :3] = corners
            data[i, 7, :3] = bary
            data[i, 8, :3] = p
        if irregular is not None:
            program = rough
            rests, directions, beta, scale = irregular
            data[:, 9:12, :3] = rests
            data[:, 12:15, :3] = directions
            program["u_irregularity"] = float(beta)
            program["u_irregularity_scale"] = float(scale)
        source = ctx.buffer(data.tobytes())
        target = ctx.buffer(reserve=len(items) * 2 * 16)
        try:
            for unit, tex in zip((WAVE["WAVE_HEIGHT_PROFILE"], WAVE["WAVE_GRADIENT_PROFILE"]),
                                 textures, strict=True):
                tex.use(location=unit)
            source.bind_to_storage_buffer(0)
            target.bind_to_storage_buffer(1)
            program.run(len(items))
            ctx.finish()
            return np.frombuffer(target.read(), np.float32).reshape(len(items), 2, 4)
        finally:
            source.release()
            target.release()

    yield run, height.astype(np.float64), gradient.astype(np.float64)
    for texture in textures:
        texture.release()


@pytest.mark.parametrize("agree", [False, True])
def test_the_blend_and_its_gradient_match_numpy(blend, agree):
    """Heights within 0.2% of the largest amplitude (the GPU's linear filtering of the
    profile tables), exact gradients within 1% of a |k| (a slope), the tangent-plane
    gradient the exact one less the weights' part; |h| never above the largest corner
    amplitude; and where the corners agree the coherence changes nothing."""
    run, height, gradient = blend
    items = cases(7 if agree else 3, agree)
    gpu = run(items)
    keeps = []
    for (waves, phases, corners, bary, p), got in zip(items, gpu, strict=True):
        h, g, keep = blend_at(waves, phases, corners, bary, p, height, gradient)
        keeps.append(keep)
        scale = waves[:, 3].max()
        slope = np.max(waves[:, 3] * np.linalg.norm(waves[:, :3], axis=1))
        assert abs(got[0, 0] - h) <= 2e-3 * scale, (got[0], h, keep)
        assert np.abs(got[0, 1:] - g).max() <= 1e-2 * slope + 1e-5, (got[0], g, keep)
        assert abs(got[1, 0] - got[0, 0]) <= 1e-6 * scale
        assert abs(got[0, 0]) <= scale * (1 + 1e-5)
    keeps = np.array(keeps)
    if agree:
        np.testing.assert_allclose(keeps, 1.0, atol=1e-6)
    else:
        # the cases exercise the coherence: a good share of them is lifted, some to the
        # floor
        assert np.mean(keeps > 1.2) > 0.2 and np.any(keeps == 1 / BLEND_COHERENCE_FLOOR)


def differences_checked(items, irregular_of=None, gain: float = 1.0) -> int:
    """numpy alone: blend_at's exact gradient against central differences of its height
    in the triangle's plane, for a cosine profile (smooth, so that the difference quotient
    converges), away from the kinks where the coherence meets its floor or the height its
    bound; ``irregular_of(i)``: case i's irregular arguments; ``gain``: the most the
    amplitudes grow (the irregular factor's 2). Returns how many differences it checked."""
    samples = 4096
    theta = 2 * np.pi * np.arange(samples) / samples
    height, gradient = np.cos(theta), -np.sin(theta)
    step = 1e-6
    checked = 0
    for index, (waves, phases, corners, bary, p) in enumerate(items):
        irregular = None if irregular_of is None else irregular_of(index)
        h, g, keep = blend_at(waves, phases, corners, bary, p, height, gradient, irregular)
        if not 1.0 < keep < 0.95 / BLEND_COHERENCE_FLOOR or abs(h) >= 0.99 * np.sum(
                bary * waves[:, 3]):
            continue
        inverse = np.linalg.inv(np.stack([corners[1] - corners[0],
                                          corners[2] - corners[0]], 1)[:2])
        slope = gain * np.max(waves[:, 3] * np.linalg.norm(waves[:, :3], axis=1))
        for axis in range(2):
            move = np.zeros(3)
            move[axis] = step
            values = []
            for sign in (1, -1):
                q = p + sign * move
                uv = inverse @ (q - corners[0])[:2]
                weights = np.array([1 - uv.sum(), uv[0], uv[1]])
                if weights.min() < 0:
                    break
                values.append(blend_at(waves, phases, corners, weights, q, height,
                                       gradient, irregular)[0])
            else:
                assert abs((values[0] - values[1]) / (2 * step) - g[axis]) <= 1e-3 * slope
                checked += 1
    return checked


def test_the_exact_gradient_is_the_gradient_of_the_height():
    """The exact gradient (with the coherence's own, and the weights') against central
    differences (differences_checked)."""
    assert differences_checked(cases(11, False)) > 100


def rest_corners(items, seed: int) -> np.ndarray:
    """Rest corners for ``items``: each posed triangle stretched back out of a random
    compression (1-3x along a random direction in its plane, as crushed cloth) and moved
    far from the origin, where the irregularity field's phases are large."""
    rng = np.random.default_rng(seed)
    out = []
    for _, _, corners, _, _ in items:
        angle = rng.uniform(0, np.pi)
        d = np.array([np.cos(angle), np.sin(angle), 0.0])
        stretch = np.eye(3) + (rng.uniform(1, 3) - 1) * np.outer(d, d)
        out.append(corners @ stretch.T + np.array([3.0, -2.0, 1.5]))
    return np.array(out)


def rest_directions(items, rests, seed: int) -> np.ndarray:
    """Per case, the corners' unit rest directions as the crush pass hands them over
    (FIELD_DIRECTION, per vertex): each corner wave's direction through the rest
    triangle's map, turned by up to 25 degrees in the rest plane (a vertex's own map is
    not its triangle's), with the wave's sign."""

    rng = np.random.default_rng(seed)
    out = []
    for (waves, _, corners, _, _), rest in zip(items, rests, strict=True):
        rest_db = weight_gradients(rest)
        normal = np.cross(rest[1] - rest[0], rest[2] - rest[0])
        normal /= np.linalg.norm(normal)
        directions = np.zeros((3, 3))
        for c in range(3):
            k = waves[c, :3]
            v = (corners[1] - corners[0]) @ k * rest_db[1] \
                + (corners[2] - corners[0]) @ k * rest_db[2]
            angle = rng.uniform(-25, 25) * np.pi / 180
            turned = v * np.cos(angle) + np.cross(normal, v) * np.sin(angle)
            directions[c] = turned / np.linalg.norm(turned)
        out.append(directions)
    return np.array(out)


#: the irregularity the cases run at (beta = IRREGULARITY_GAIN x it) and their field's
#: 1 / Lambda: Lambda 1.5 units, over the cases' 0.2-1.5 unit waves, so that the factor
#: |k| / |k'| reaches its clamps on some corners
IRREGULARITY = 0.3
SCALE = 1 / 1.5


def test_the_irregular_blend_and_its_gradient_match_numpy(blend):
    """The IRREGULAR variant (wrinkle:irregularity) against blend_at's: heights and exact
    gradients as the regular variant's test bounds them, over triangles whose rest
    corners lie 4 units from the origin; and the field is not nothing there (the heights
    differ from the regular blend's)."""
    from usdwrinkle.method.contract import IRREGULARITY_GAIN

    run, height, gradient = blend
    items = cases(5, False)
    rests = rest_corners(items, 6)
    directions = rest_directions(items, rests, 8)
    beta = IRREGULARITY_GAIN * IRREGULARITY
    gpu = run(items, (rests, directions, beta, SCALE))
    moved = []
    for (waves, phases, corners, bary, p), rest, u, got in zip(items, rests, directions, gpu,
                                                              strict=True):
        h, g, _ = blend_at(waves, phases, corners, bary, p, height, gradient,
                           (rest, u, beta, SCALE))
        regular = blend_at(waves, phases, corners, bary, p, height, gradient)[0]
        scale = waves[:, 3].max() * 2  # the factor raises an amplitude at most 2x
        slope = np.max(waves[:, 3] * np.linalg.norm(waves[:, :3], axis=1)) * 2
        assert abs(got[0, 0] - h) <= 2e-3 * scale, (got[0], h)
        assert np.abs(got[0, 1:] - g).max() <= 1e-2 * slope + 1e-5, (got[0], g)
        moved.append(abs(h - regular) / waves[:, 3].max())
    assert np.median(moved) > 0.1
    # a wave's sign is arbitrary: (-k, -phi) at every corner (and its rest direction
    # with it, as corner_waves flips them) draws the same folds (the default profile is
    # even), as the regular blend does; a field added to the phase alike whatever the sign
    # drew other folds after a flip (2026-12-05: a held sleeve's crests jumped when a
    # triangle's first corner changed its sign)
    flipped = [(np.concatenate([-waves[:, :3], waves[:, 3:]], 1), -phases, corners, bary, p)
               for waves, phases, corners, bary, p in items]
    again = run(flipped, (rests, -directions, beta, SCALE))
    scale = np.array([w[:, 3].max() for w, *_ in items])
    assert np.all(np.abs(again[:, 0, 0] - gpu[:, 0, 0]) <= 2e-3 * scale)


def test_the_irregular_exact_gradient_is_the_gradient_of_the_height():
    """As the regular test: the IRREGULAR exact gradient (the shift's second derivatives
    in the amplitude factor's) against central differences."""
    from usdwrinkle.method.contract import IRREGULARITY_FACTOR_MAX, IRREGULARITY_GAIN

    beta = IRREGULARITY_GAIN * IRREGULARITY
    items = cases(13, False)
    rests = rest_corners(items, 14)
    directions = rest_directions(items, rests, 15)
    assert differences_checked(items, lambda i: (rests[i], directions[i], beta, SCALE),
                               IRREGULARITY_FACTOR_MAX) > 100


def test_the_deepening_adds_its_carried_offset_and_gradient(blend):
    """The deepened pleats (method/deepen.py): the blend adds each corner's offset o_c
    carried to p along its gradient g_c, o_c + g_c.(p - P_c), blended by the barycentric
    weights, to h; to the exact gradient the blended g_c and the weights' part (the
    carried offsets times the weights' gradients), so it is the gradient of the height it
    adds; to the tangent-plane one the blended g_c, projected into the plane."""
    run, height, gradient = blend
    items = cases(11, False)
    rng = np.random.default_rng(12)
    deepen = np.zeros((len(items), 3, 4), np.float32)
    deepen[:, :, 0] = rng.uniform(-0.1, 0.1, (len(items), 3))
    deepen[:, :, 1:] = rng.uniform(-0.5, 0.5, (len(items), 3, 3))
    plain, deepened = run(items), run(items, deepen=deepen)
    for (waves, phases, corners, bary, p), off, got, base in zip(items, deepen, deepened,
                                                                 plain, strict=True):
        h, g, _ = blend_at(waves, phases, corners, bary, p, height, gradient)
        grads = off[:, 1:].astype(np.float64)
        carried = off[:, 0] + np.sum(grads * (p - corners), 1)
        o = bary @ carried
        go = bary @ grads
        exact = go + carried @ weight_gradients(corners)
        scale = waves[:, 3].max()
        slope = np.max(waves[:, 3] * np.linalg.norm(waves[:, :3], axis=1))
        assert abs(got[0, 0] - (h + o)) <= 2e-3 * scale, (got[0], h, o)
        assert np.abs(got[0, 1:] - (g + exact)).max() <= 1e-2 * slope + 1e-5, (got[0], g)
        n = np.cross(corners[1] - corners[0], corners[2] - corners[0])
        n /= np.linalg.norm(n)
        tangent = (base[1, 1:] + go) - np.dot(base[1, 1:] + go, n) * n
        np.testing.assert_allclose(got[1, 1:], tangent, atol=1e-5)
        assert abs(got[1, 0] - got[0, 0]) <= 1e-6 * scale + 1e-6
