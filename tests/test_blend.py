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
from usdwrinkle.reference.blend import blend_at
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

    def run(items):
        data = np.zeros((len(items), 9, 4), np.float32)
        for i, (waves, phases, corners, bary, p) in enumerate(items):
            data[i, :3] = waves
            data[i, 3, :3] = phases
            data[i, 4:7, :3] = corners
            data[i, 7, :3] = bary
            data[i, 8, :3] = p
        source = ctx.buffer(data.tobytes())
        target = ctx.buffer(reserve=len(items) * 2 * 16)
        try:
            for unit, tex in zip((WAVE["WAVE_HEIGHT_PROFILE"], WAVE["WAVE_GRADIENT_PROFILE"]),
                                 textures, strict=True):
                tex.use(location=unit)
            source.bind_to_storage_buffer(0)
            target.bind_to_storage_buffer(1)
            shader.run(len(items))
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


def test_the_exact_gradient_is_the_gradient_of_the_height():
    """numpy alone: the exact gradient (with the coherence's own, and the weights')
    against central differences of the height in the triangle's plane, for a cosine
    profile (smooth, so that the difference quotient converges), away from the kinks
    where the coherence meets its floor or the height its bound."""
    samples = 4096
    theta = 2 * np.pi * np.arange(samples) / samples
    height, gradient = np.cos(theta), -np.sin(theta)
    step = 1e-6
    checked = 0
    for waves, phases, corners, bary, p in cases(11, False):
        h, g, keep = blend_at(waves, phases, corners, bary, p, height, gradient)
        if not 1.0 < keep < 0.95 / BLEND_COHERENCE_FLOOR or abs(h) >= 0.99 * np.sum(
                bary * waves[:, 3]):
            continue
        inverse = np.linalg.inv(np.stack([corners[1] - corners[0],
                                          corners[2] - corners[0]], 1)[:2])
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
                                       gradient)[0])
            else:
                slope = np.max(waves[:, 3] * np.linalg.norm(waves[:, :3], axis=1))
                assert abs((values[0] - values[1]) / (2 * step) - g[axis]) <= 1e-3 * slope
                checked += 1
    assert checked > 100
