"""Blender's MikkTSpace tangents (``Mesh.calc_tangents``) of triangle meshes: the oracle
for usdwrinkle's vectorised MikkTSpace (src/usdwrinkle/maps/tangents.py).

Runs in a Python that has Blender's ``bpy`` wheel; realclients/__init__.py starts it:

    python tangents_client.py JOBS.json

JOBS.json: a list of {"mesh": an .npz with points (n, 3), triangles (t, 3), normals
(3t, 3: the unit normal of each corner) and uv (3t, 2), "out": an .npz to write with
tangent (3t, 3), sign (3t,) and normal (3t, 3: the corner normals Blender used)}. The
faces are shaded smooth, the normals set as custom normals (Blender stores them
compressed: within 0.4 degrees). One line "ok OUT" or "failed OUT: reason" per job.
"""
from __future__ import annotations

import sys


def tangents(job: dict) -> None:
    import bpy
    import numpy as np

    data = np.load(job["mesh"])
    mesh = bpy.data.meshes.new("mesh")
    mesh.from_pydata(data["points"].tolist(), [], data["triangles"].tolist())
    mesh.update()
    mesh.shade_smooth()  # a flat face is its own MikkTSpace group in Blender
    layer = mesh.uv_layers.new(name="st")
    layer.data.foreach_set("uv", np.asarray(data["uv"], np.float32).reshape(-1))
    mesh.normals_split_custom_set(np.asarray(data["normals"], np.float64).tolist())
    mesh.calc_tangents(uvmap="st")
    count = len(mesh.loops)
    tangent = np.zeros(3 * count, np.float32)
    sign = np.zeros(count, np.float32)
    normal = np.zeros(3 * count, np.float32)
    mesh.loops.foreach_get("tangent", tangent)
    mesh.loops.foreach_get("bitangent_sign", sign)
    mesh.loops.foreach_get("normal", normal)
    np.savez(job["out"], tangent=tangent.reshape(-1, 3), sign=sign,
             normal=normal.reshape(-1, 3))


def main(jobs_path: str) -> None:
    import client_jobs

    client_jobs.run(client_jobs.load(jobs_path), tangents)
    client_jobs.finish()

if __name__ == "__main__":
    main(sys.argv[1])
