"""What Blender's USD importer makes of a stage's materials (and, on request, of its
skinning): for each mesh object, the materials it gets and the image files that feed its
Normal Map nodes. The oracle for which material binding Blender resolves (bake --maps
binds a map set per purpose).

Runs in a Python that has Blender's ``bpy`` wheel; realclients/__init__.py starts it:

    python import_client.py JOBS.json

JOBS.json: a list of {"stage": a USD file, "out": a .json to write with {object name:
{"materials": [material names], "normal_images": [file names of the images that feed a
Normal Map node], "base_colours": [the Principled BSDFs' Base Color, RGBA],
"image_sequences": [file names of the image sequences its nodes read], and where the job
lists frames in "points_at": "preserve_volume": [each Armature modifier's Preserve
Volume], "points": {frame: the evaluated mesh's world points in Blender's axes and
units}}}, "addon": optional, as in cycles_client.py}. One line "ok OUT" or "failed OUT:
reason" per job.
"""
from __future__ import annotations

import sys


def imported(job: dict) -> None:
    import json
    import os

    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    hook = None
    if job.get("addon"):
        import addon

        hook = addon.register(job["addon"])
    try:
        bpy.ops.wm.usd_import(filepath=job["stage"])
    finally:
        if hook is not None:
            hook.unregister()
    found = {}
    for obj in bpy.data.objects:
        if obj.type != "MESH":
            continue
        materials, images, colours, sequences = [], [], [], []
        for slot in obj.material_slots:
            material = slot.material
            if material is None:
                continue
            materials.append(material.name)
            nodes = material.node_tree.nodes if material.use_nodes else []
            for node in nodes:
                if node.type == "TEX_IMAGE" and node.image is not None and \
                        node.image.source == "SEQUENCE":
                    sequences.append(os.path.basename(node.image.filepath))
                if node.type == "BSDF_PRINCIPLED":
                    colours.append([round(c, 4) for c in node.inputs["Base Color"].default_value])
                if node.type != "NORMAL_MAP":
                    continue
                images += [os.path.basename(upstream.image.filepath)
                           for upstream in _upstream(node) if upstream.type == "TEX_IMAGE"
                           and upstream.image is not None]
        found[obj.name] = {"materials": materials, "normal_images": images,
                           "base_colours": colours, "image_sequences": sorted(sequences)}
        if job.get("points_at"):
            found[obj.name].update(
                preserve_volume=[m.use_deform_preserve_volume
                                 for m in obj.modifiers if m.type == "ARMATURE"], points={})
    for frame in job.get("points_at") or ():
        bpy.context.scene.frame_set(int(frame))
        depsgraph = bpy.context.evaluated_depsgraph_get()
        for obj in bpy.data.objects:
            if obj.type == "MESH":
                evaluated = obj.evaluated_get(depsgraph)
                found[obj.name]["points"][str(frame)] = [
                    list(evaluated.matrix_world @ vertex.co)
                    for vertex in evaluated.data.vertices]
    with open(job["out"], "w", encoding="utf-8") as handle:
        json.dump(found, handle)


def _upstream(node, seen=None):
    """Every node that feeds ``node``, through any number of links (the importer puts
    scale and bias nodes between the texture and the Normal Map node)."""
    seen = set() if seen is None else seen
    for socket in node.inputs:
        for link in socket.links:
            source = link.from_node
            if source.name not in seen:
                seen.add(source.name)
                yield source
                yield from _upstream(source, seen)


def main(jobs_path: str) -> None:
    import client_jobs

    client_jobs.run(client_jobs.load(jobs_path), imported)
    client_jobs.finish()


if __name__ == "__main__":
    main(sys.argv[1])
