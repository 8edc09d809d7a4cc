"""Run one cloth shot in Blender's cloth solver; runs in a Python with Blender's bpy wheel.

    python sim_client.py SHOT.npz OUT.npz

SHOT.npz (benchmarks/physics/simulate.py writes it): ``rest`` (n, 3), ``quads`` (m, 4),
``pinned`` (n,) bool, ``key_frames`` (k,), ``key_points`` (k, n, 3) where the pins are at
those frames (linear in between, through relative shape keys, which Blender's cloth pins
follow), ``frames``, ``gravity``, ``preset`` (a file of Blender's presets/cloth). OUT.npz
gets ``points`` (frames, n, 3), frame 1 first, and ``seconds``.
"""
from __future__ import annotations

import os
import sys
import time

import bpy  # noqa: F401 (Blender first)
import numpy as np


def preset_values(name: str) -> dict:
    """The settings a Blender cloth preset file sets (scripts/presets/cloth/NAME.py)."""
    folder = os.path.join(bpy.utils.resource_path("LOCAL"), "scripts", "presets", "cloth")
    values = {}
    with open(os.path.join(folder, f"{name}.py"), encoding="utf-8") as handle:
        for line in handle:
            prefix = "bpy.context.cloth.settings."
            if line.startswith(prefix):
                key, _, value = line[len(prefix):].partition(" = ")
                values[key.strip()] = eval(value.strip(), {})  # noqa: S307 (Blender's file)
    return values


def main(shot_path: str, out_path: str) -> None:
    shot = np.load(shot_path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    rest = shot["rest"]
    mesh = bpy.data.meshes.new("cloth")
    mesh.from_pydata(rest.tolist(), [], shot["quads"].tolist())
    obj = bpy.data.objects.new("cloth", mesh)
    scene = bpy.context.scene
    scene.collection.objects.link(obj)
    group = obj.vertex_groups.new(name="pin")
    group.add(np.flatnonzero(shot["pinned"]).tolist(), 1.0, "REPLACE")

    key_frames = [int(f) for f in shot["key_frames"]]
    _animate(obj, key_frames, shot["key_points"], int(shot["frames"]))
    if "collider_rest" in shot.files:
        arm_mesh = bpy.data.meshes.new("arm")
        arm_mesh.from_pydata(shot["collider_rest"].tolist(), [],
                             shot["collider_quads"].tolist())
        arm = bpy.data.objects.new("arm", arm_mesh)
        scene.collection.objects.link(arm)
        _animate(arm, key_frames, shot["collider_keys"], int(shot["frames"]))
        arm.modifiers.new("collision", "COLLISION")
        arm.collision.thickness_outer = 0.005
        arm.collision.cloth_friction = 5.0

    modifier = obj.modifiers.new("cloth", "CLOTH")
    settings = modifier.settings
    for key, value in preset_values(str(shot["preset"])).items():
        setattr(settings, key, value)
    settings.vertex_group_mass = "pin"
    if "quality" in shot.files:
        settings.quality = int(shot["quality"])
    modifier.collision_settings.distance_min = 0.005
    if "self_collision" in shot.files and bool(shot["self_collision"]):
        modifier.collision_settings.use_self_collision = True
        modifier.collision_settings.self_distance_min = 0.004
    if not bool(shot["gravity"]):
        scene.use_gravity = False
    frames = int(shot["frames"])
    scene.frame_start, scene.frame_end = 1, frames
    modifier.point_cache.frame_start, modifier.point_cache.frame_end = 1, frames

    out = np.empty((frames, len(rest), 3), np.float32)
    flat = np.empty(len(rest) * 3, np.float32)
    started = time.perf_counter()
    for frame in range(1, frames + 1):
        scene.frame_set(frame)
        evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        evaluated.data.vertices.foreach_get("co", flat)
        out[frame - 1] = flat.reshape(-1, 3)
    np.savez_compressed(out_path, points=out, seconds=time.perf_counter() - started)


def _animate(obj, key_frames, key_points, last_frame) -> None:
    """Relative shape keys, one per key after the first (the rest), each 1 at its frame
    and 0 at its neighbours', linear between: the points move from key to key."""
    obj.shape_key_add(name="Basis")
    for k in range(1, len(key_frames)):
        block = obj.shape_key_add(name=f"key{k}")
        block.data.foreach_set("co", key_points[k].astype(np.float32).ravel())
        neighbours = [key_frames[k - 1], key_frames[k]]
        if k + 1 < len(key_frames):
            neighbours.append(key_frames[k + 1])
        for frame in neighbours:
            block.value = 1.0 if frame == key_frames[k] else 0.0
            block.keyframe_insert("value", frame=frame)
        if k + 1 == len(key_frames):  # the last key holds
            block.value = 1.0
            block.keyframe_insert("value", frame=last_frame)
    action = obj.data.shape_keys.animation_data.action
    for curve in _fcurves(action):
        for point in curve.keyframe_points:
            point.interpolation = "LINEAR"


def _fcurves(action):
    """An action's F-curves (Blender 5 keeps them in layered channelbags)."""
    if hasattr(action, "fcurves"):
        return list(action.fcurves)
    curves = []
    for layer in action.layers:
        for strip in layer.strips:
            for bag in strip.channelbags:
                curves.extend(bag.fcurves)
    return curves


if __name__ == "__main__":
    try:
        main(sys.argv[1], sys.argv[2])
        code = 0
    except Exception as exc:  # noqa: BLE001 (reported, then the hard exit)
        import traceback

        traceback.print_exc()
        print(f"failed: {type(exc).__name__}: {exc}", file=sys.stderr)
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
