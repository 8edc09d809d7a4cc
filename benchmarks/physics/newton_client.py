"""Run one cloth shot in Newton's VBD cloth solver; runs in a Python with ``newton``
(benchmarks/physics/README: ``.venv-newton``, or USDWRINKLE_NEWTON_PYTHON).

    python newton_client.py SHOT.npz OUT.npz

SHOT.npz (benchmarks/physics/simulate.py writes it): ``rest`` (n, 3), ``quads`` (m, 4),
``pinned`` (n,) bool, ``key_frames`` (k,), ``key_points`` (k, n, 3) where the pins are at
those frames (linear in between), ``frames``, ``gravity``, and the cloth in physical units:
``bending`` D (N m), ``density`` (kg/m^2), ``stretch`` (N/m, the membrane's Lame mu; lambda
the same), ``thickness`` (m, the self-contact distance). Optional: ``collider_*`` (an
animated closed mesh the cloth rests against: points at the same keys), ``substeps``,
``iterations``, ``fps``, ``noise_seed``. OUT.npz gets ``points`` (frames, n, 3), frame 1
first, ``seconds`` and ``stretch_p99`` (the 99th percentile of |edge length / rest - 1| at
the last frame: how inextensible the solve left the cloth).

Long runs (a 0.5 cm sleeve at 160 iterations: hours here) outlast a working session. Every
NEWTON_CLIENT_CHECKPOINT_FRAMES frames (10; 0: never) the client saves the frames so far
and the cloth's positions and velocities (and the arm's pose) beside OUT, as
OUT.resume.npz; a run with the same OUT goes on from there (simulate.py's OUT is named by
the shot's arrays and the solver's options, so only the same simulation resumes), and the
finished run removes it. The solver's own scratch (contacts, the colouring) is built
again: a resumed run is the same simulation, not bit for bit the same numbers (the 2 cm
cotton sleeve stopped at frame 33 and resumed from frame 30: 0.17 mm RMS from the
uninterrupted run two frames later, 1.5 mm at frame 70, where its folds are 5.5 mm tall).

Bending in physical units: Newton's VBD bends each interior edge e with the energy
0.5 ke |e| (theta - theta0)^2. A smooth surface bent to curvature kappa across an edge whose
two triangles' centroids lie l_e apart turns by theta = kappa l_e, and the patch the edge
stands for has area |e| l_e, so D kappa^2 / 2 per area gives ke = D / l_e per edge (the
dual length l_e = (area of its two triangles) / (3 |e| / 2)... taken from the rest mesh
per edge below). So halving the grid spacing keeps the cloth's D, and the folds converge.
"""
from __future__ import annotations

import os
import sys
import time

import numpy as np


def triangles(quads: np.ndarray) -> np.ndarray:
    """Each quad split along alternating diagonals (a checkerboard), so that the folds do
    not line up along one family of diagonals."""
    quads = np.asarray(quads, np.int64)
    flip = (np.arange(len(quads)) + (np.arange(len(quads)) // max(1, _row_length(quads)))) % 2
    a = np.stack([quads[:, 0], quads[:, 1], quads[:, 2], quads[:, 0], quads[:, 2],
                  quads[:, 3]], 1)
    b = np.stack([quads[:, 0], quads[:, 1], quads[:, 3], quads[:, 1], quads[:, 2],
                  quads[:, 3]], 1)
    return np.where(flip[:, None] == 0, a, b).reshape(-1, 3)


def _row_length(quads: np.ndarray) -> int:
    """Quads per grid row (the first jump in the first corner's index)."""
    jumps = np.flatnonzero(np.diff(quads[:, 0]) != 1)
    return int(jumps[0] + 1) if len(jumps) else len(quads)


def edge_dual_lengths(rest: np.ndarray, tris: np.ndarray) -> dict:
    """For each interior edge (a sorted vertex pair), the distance between the centroids of
    its two triangles: the length over which its hinge stands for the smooth curvature."""
    centroids = rest[tris].mean(1)
    seen: dict = {}
    for t, tri in enumerate(tris):
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            key = (min(a, b), max(a, b))
            seen.setdefault(key, []).append(t)
    return {key: float(np.linalg.norm(centroids[ts[0]] - centroids[ts[1]]))
            for key, ts in seen.items() if len(ts) == 2}


def main(shot_path: str, out_path: str) -> None:
    import warp as wp

    wp.config.quiet = True
    wp.init()
    import newton

    shot = np.load(shot_path)
    rest = shot["rest"].astype(np.float64)
    # the cloth's own shape (no noise): its rest lengths and rest angles; the shot's
    # noisy rest is where it starts
    clean = shot["clean"].astype(np.float64) if "clean" in shot.files else rest
    tris = triangles(shot["quads"])
    pinned = shot["pinned"].astype(bool)
    fps = float(shot["fps"]) if "fps" in shot.files else 60.0
    substeps = int(shot["substeps"]) if "substeps" in shot.files else 10
    iterations = int(shot["iterations"]) if "iterations" in shot.files else 10
    bending = float(shot["bending"])
    density = float(shot["density"])
    stretch = float(shot["stretch"])
    thickness = float(shot["thickness"])

    builder = newton.ModelBuilder(up_axis="Z", gravity=(0.0, 0.0, -9.81) if bool(shot["gravity"])
                                  else (0.0, 0.0, 0.0))
    builder.add_cloth_mesh(pos=wp.vec3(0.0, 0.0, 0.0), rot=wp.quat_identity(), scale=1.0,
                           vel=wp.vec3(0.0, 0.0, 0.0),
                           vertices=[wp.vec3(*p) for p in clean],
                           indices=tris.ravel().tolist(), density=density,
                           tri_ke=stretch, tri_ka=stretch, tri_kd=1e-3 * stretch,
                           edge_ke=1.0, edge_kd=0.0, particle_radius=thickness)
    # bending in N m: each hinge's stiffness is D over its dual length (see the docstring)
    dual = edge_dual_lengths(clean, tris)
    for index in range(len(builder.edge_indices)):
        o1, o2, a, b = builder.edge_indices[index]
        if o1 < 0 or o2 < 0:
            continue
        length = dual.get((min(a, b), max(a, b)))
        if length:
            builder.edge_bending_properties[index] = (bending / length,
                                                      builder.edge_bending_properties[index][1])
    for i in np.flatnonzero(pinned):
        builder.particle_mass[i] = 0.0
        builder.particle_flags[i] = builder.particle_flags[i] & ~int(newton.ParticleFlags.ACTIVE)

    # the arm: kinematic capsules, posed per substep from the keys (capsules, 7): p0, p1, r
    capsules = shot["capsules"].astype(np.float64) if "capsules" in shot.files else None
    bodies = []
    if capsules is not None:
        cfg = builder.default_shape_cfg.copy()
        cfg.mu = 0.5
        for c in capsules[0]:
            body = builder.add_body(is_kinematic=True)
            half = 0.5 * float(np.linalg.norm(c[3:6] - c[0:3]))
            builder.add_shape_capsule(body, radius=float(c[6]), half_height=half, cfg=cfg)
            bodies.append(body)
    builder.color(include_bending=True)
    model = builder.finalize()
    model.soft_contact_ke = 1e3
    model.soft_contact_kd = 1e-2
    model.soft_contact_mu = 0.5

    solver = newton.solvers.SolverVBD(model=model, iterations=iterations,
                                      particle_enable_self_contact=True,
                                      particle_self_contact_margin=thickness,
                                      particle_self_contact_gap=thickness)
    state_0, state_1 = model.state(), model.state()
    state_0.particle_q.assign(rest.astype(np.float32))
    control = model.control()
    pipeline = newton.CollisionPipeline(model) if bodies else None
    contacts = pipeline.contacts() if pipeline is not None else None

    key_frames = shot["key_frames"].astype(np.float64)
    key_points = shot["key_points"].astype(np.float64)
    frames = int(shot["frames"])
    dt = 1.0 / fps / substeps
    pins = np.flatnonzero(pinned)

    def pins_at(frame: float) -> np.ndarray:
        k = int(np.clip(np.searchsorted(key_frames, frame, side="right") - 1, 0,
                        len(key_frames) - 1))
        if k + 1 >= len(key_frames):
            return key_points[-1][pins]
        t = (frame - key_frames[k]) / (key_frames[k + 1] - key_frames[k])
        return ((1 - t) * key_points[k] + t * key_points[k + 1])[pins]

    def capsule_poses(frame: float) -> np.ndarray:
        """(capsules, 7): each capsule's centre and the quaternion (x, y, z, w) that
        turns its local z onto its axis, the keys' capsules interpolated linearly."""
        k = int(np.clip(np.searchsorted(key_frames, frame, side="right") - 1, 0,
                        len(key_frames) - 1))
        if k + 1 >= len(key_frames):
            c = capsules[-1]
        else:
            t = (frame - key_frames[k]) / (key_frames[k + 1] - key_frames[k])
            c = (1 - t) * capsules[k] + t * capsules[k + 1]
        centre = 0.5 * (c[:, 0:3] + c[:, 3:6])
        axis = c[:, 3:6] - c[:, 0:3]
        axis /= np.linalg.norm(axis, axis=1, keepdims=True)
        z = np.array([0.0, 0.0, 1.0])
        half = z + axis
        half /= np.linalg.norm(half, axis=1, keepdims=True)
        xyz = np.cross(z, half)
        w = half @ z
        return np.concatenate([centre, xyz, w[:, None]], 1)

    if bodies:
        body_q = state_0.body_q.numpy()
        body_q[bodies] = capsule_poses(1.0)
        state_0.body_q.assign(body_q)

    out = np.empty((frames, len(rest), 3), np.float32)
    started = time.perf_counter()
    out[0] = state_0.particle_q.numpy()
    # a run that was stopped goes on from its last checkpoint (the module docstring)
    checkpoint = out_path + ".resume.npz"
    every = int(os.environ.get("NEWTON_CLIENT_CHECKPOINT_FRAMES", "10"))
    first, spent = 2, 0.0
    if os.path.exists(checkpoint):
        saved = np.load(checkpoint)
        if saved["points"].shape[1:] == out.shape[1:] and int(saved["frames"]) == frames:
            done = int(saved["frame"])
            out[:done] = saved["points"][:done]
            state_0.particle_q.assign(saved["particle_q"])
            state_0.particle_qd.assign(saved["particle_qd"])
            if bodies:
                state_0.body_q.assign(saved["body_q"])
            first, spent = done + 1, float(saved["seconds"])
            print(f"resumed at frame {first} of {frames}", file=sys.stderr, flush=True)
    for frame in range(first, frames + 1):
        for sub in range(substeps):
            at = frame - 1 + (sub + 1) / substeps
            q = state_0.particle_q.numpy()
            q[pins] = pins_at(at)
            state_0.particle_q.assign(q)
            qd = state_0.particle_qd.numpy()
            qd[pins] = 0.0
            state_0.particle_qd.assign(qd)
            if bodies:
                body_q = state_0.body_q.numpy()
                body_q[bodies] = capsule_poses(at)
                state_0.body_q.assign(body_q)
                state_0.body_qd.assign(np.zeros_like(state_0.body_qd.numpy()))
            state_0.clear_forces()
            if pipeline is not None:
                pipeline.collide(state_0, contacts)
            solver.step(state_0, state_1, control, contacts, dt)
            state_0, state_1 = state_1, state_0
        out[frame - 1] = state_0.particle_q.numpy()
        if os.environ.get("NEWTON_CLIENT_PROGRESS"):
            print(f"frame {frame}/{frames} {time.perf_counter() - started:.1f}s",
                  file=sys.stderr, flush=True)
        if every > 0 and frame % every == 0 and frame < frames:
            partial = checkpoint + ".tmp.npz"
            np.savez(partial, points=out[:frame], frame=frame, frames=frames,
                     particle_q=state_0.particle_q.numpy(),
                     particle_qd=state_0.particle_qd.numpy(),
                     body_q=state_0.body_q.numpy() if bodies else np.zeros(0),
                     seconds=spent + time.perf_counter() - started)
            os.replace(partial, checkpoint)
    last = out[-1].astype(np.float64)
    edges = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    strain = np.abs(np.linalg.norm(last[edges[:, 0]] - last[edges[:, 1]], axis=1)
                    / np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1) - 1.0)
    np.savez_compressed(out_path, points=out, seconds=spent + time.perf_counter() - started,
                        stretch_p99=float(np.percentile(strain, 99)))
    if os.path.exists(checkpoint):
        os.remove(checkpoint)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
