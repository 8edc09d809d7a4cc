"""Render USD stages with Blender (Cycles or EEVEE) through its USD importer.

Runs in a Python that has Blender's ``bpy`` wheel, never in usdwrinkle's own process
(the two USD builds cannot share one). realclients/__init__.py starts it:

    python cycles_client.py JOBS.json

JOBS.json: a list of {"stage", "camera" (prim path), "frame", "width", "height",
"out" (.exr: a multilayer EXR with the combined image and the Normal pass, world space
in the stage's axes; .png: the combined image, 8-bit, Standard view transform),
"camera_light" (the strength of a sun along the camera's view, as usdview's head-light;
default none), "light_scale" (the importer's light_intensity_scale, default 1),
"subdivision" (import subdivision surfaces as such; default false: the coarse mesh, as
usdview's default complexity shows it), "engine" ("CYCLES", default, or "BLENDER_EEVEE"),
"samples" (default 16), "world" (a linear RGB: the world's uniform radiance, as a dome
light without a texture; default: the importer's world, or Blender's dark grey),
"shadows" (default true: false turns every light's shadows off, and every object's
visibility to diffuse, glossy and shadow rays, as usdwrinkle and Storm draw without
occlusion or inter-reflection), "addon" (the path of usdwrinkle's Blender add-on,
installed and enabled for the job as a user does: realclients/addon.py; default none),
"purposes" (default ["default", "proxy"]: Blender's importer defaults; add "render" for
the geometry layer's render mesh), "decoded" (default false: with an .exr, a shader AOV
"Decoded" holds the world-space output of every Normal Map node, the normal decoded from
the map before the BSDF's ensure_valid_specular_reflection tilts it: Cycles' decoded
normal itself, where the Normal pass shows what the BSDF shades with), "backfacing"
(default false: with an .exr, a shader AOV "Backfacing" holds the share of the pixel's
samples that hit a back face, the Geometry node's Backfacing output in every material:
Cycles negates a back face's normal-map normal whole, where Storm and usdwrinkle keep its
tangent and bitangent and turn only the normal, so the two are compared apart)}. One line "ok OUT"
or "failed OUT: reason" per job on stdout, and "seconds S OUT": the time the render took.

The importer converts a Y-up stage to Blender's Z-up by rotating the root objects; the
Normal pass is turned back into the stage's axes, so that it compares with usdwrinkle's.
"""
from __future__ import annotations

import os
import sys


def render(job: dict) -> None:
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    hook = None
    if job.get("addon"):
        import addon

        hook = addon.register(job["addon"])
    try:
        _import_and_render(job)
    finally:
        if hook is not None:  # the next job imports as it says, with or without it
            hook.unregister()


def _import_and_render(job: dict) -> None:
    import bpy

    purposes = set(job.get("purposes") or ["default", "proxy"])
    bpy.ops.wm.usd_import(filepath=job["stage"], set_frame_range=True,
                          import_proxy="proxy" in purposes,
                          import_render="render" in purposes, import_guide=False,
                          import_usd_preview=True,
                          light_intensity_scale=float(job.get("light_scale", 1.0)),
                          import_subdivision=bool(job.get("subdivision", False)))
    scene = bpy.context.scene
    turn_lights_to_blender_axes(job["stage"])
    camera_name = job["camera"].rstrip("/").rsplit("/", 1)[-1]
    cameras = [o for o in scene.objects if o.type == "CAMERA"]
    camera = next((o for o in cameras if o.name == camera_name or
                   o.data.name == camera_name), None)
    if camera is None:
        raise RuntimeError(f"no camera {camera_name} among {[o.name for o in cameras]}")
    scene.camera = camera
    if job.get("camera_light"):
        # usdview's default head-light: a sun along the camera's view
        light = bpy.data.objects.new("HeadLight", bpy.data.lights.new("HeadLight", "SUN"))
        light.data.energy = float(job["camera_light"])
        light.parent = camera
        scene.collection.objects.link(light)
    if not job.get("shadows", True):
        for light in bpy.data.lights:
            light.use_shadow = False
        for obj in scene.objects:  # nor does a mesh occlude or reflect light onto another
            if obj.type == "MESH":  # (a lamp's own visibility would switch its light off)
                obj.visible_diffuse = obj.visible_glossy = obj.visible_shadow = False
    scene.frame_set(int(round(float(job["frame"]))))
    scene.render.engine = job.get("engine", "CYCLES")
    scene.render.resolution_x = int(job["width"])
    scene.render.resolution_y = int(job["height"])
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    if scene.render.engine == "CYCLES":
        scene.cycles.device = "CPU"
        scene.cycles.samples = int(job.get("samples", 16))
        scene.cycles.use_denoising = False
        scene.cycles.pixel_filter_type = "BOX"
    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    if job.get("world"):
        uniform_world(scene.world, job["world"])
    exr = job["out"].endswith(".exr")
    if exr and job.get("decoded"):
        decoded_aov(scene)
    if exr and job.get("backfacing"):
        backfacing_aov(scene)
    if exr:
        scene.view_layers[0].use_pass_normal = True
        scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
        scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
        scene.render.image_settings.color_depth = "32"
    else:
        scene.render.image_settings.file_format = "PNG"
        scene.render.image_settings.color_mode = "RGBA"
    scene.render.filepath = job["out"]
    bpy.ops.render.render(write_still=True)
    if not os.path.isfile(job["out"]):
        raise RuntimeError("Blender wrote no image")


def turn_lights_to_blender_axes(stage_path: str) -> None:
    """Blender 5.0.1's importer turns a Y-up stage's meshes and cameras into its Z-up world
    but not its lights (measured: the shirt's key light pointed along its stage direction
    in Blender's axes, so the folds were lit from elsewhere than in Storm and usdwrinkle).
    Each imported light that kept its stage direction gets the same +90 degree turn about
    x as the rest of the stage."""
    import math

    import bpy
    from mathutils import Matrix, Vector

    if hasattr(bpy.utils, "expose_bundled_modules"):
        bpy.utils.expose_bundled_modules()
    from pxr import Gf, Usd, UsdGeom, UsdLux

    stage = Usd.Stage.Open(stage_path)
    if UsdGeom.GetStageUpAxis(stage) != UsdGeom.Tokens.y:
        return
    turn = Matrix.Rotation(math.radians(90.0), 4, "X")
    lights = {o.name.split(".")[0]: o for o in bpy.context.scene.objects if o.type == "LIGHT"}
    for prim in stage.Traverse():
        if not prim.HasAPI(UsdLux.LightAPI) or prim.GetName() not in lights:
            continue
        obj = lights[prim.GetName()]
        usd = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
        stage_direction = Vector(usd.TransformDir(Gf.Vec3d(0, 0, -1)).GetNormalized())
        blender_direction = (obj.matrix_world.to_3x3() @ Vector((0, 0, -1))).normalized()
        if blender_direction.dot(stage_direction) > 0.999:  # not turned by the importer
            obj.matrix_world = turn @ obj.matrix_world


def uniform_world(world, colour) -> None:
    """The world lights every direction with radiance ``colour`` (linear RGB): a
    UsdLux dome light without a texture, whose colour x intensity it is (Blender's
    importer makes no world of such a dome)."""
    world.use_nodes = True
    background = next(n for n in world.node_tree.nodes if n.type == "BACKGROUND")
    background.inputs["Color"].default_value = (*[float(c) for c in colour], 1.0)
    background.inputs["Strength"].default_value = 1.0


def _materials(scene) -> set:
    return {slot.material for o in scene.objects for slot in o.material_slots
            if slot.material is not None and slot.material.node_tree is not None}


def decoded_aov(scene) -> None:
    """A shader AOV "Decoded" fed by each material's Normal Map node (the importer makes
    one per UsdPreviewSurface whose normal input reads a texture)."""
    aov = scene.view_layers[0].aovs.add()
    aov.name, aov.type = "Decoded", "COLOR"
    for material in _materials(scene):
        tree = material.node_tree
        for node in [n for n in tree.nodes if n.type == "NORMAL_MAP"]:
            out = tree.nodes.new("ShaderNodeOutputAOV")
            out.aov_name = "Decoded"
            tree.links.new(node.outputs["Normal"], out.inputs["Color"])


def backfacing_aov(scene) -> None:
    """A shader AOV "Backfacing" fed by a Geometry node's Backfacing output in every
    material: averaged over the pixel's samples, the share that hit a back face (a mesh
    without a material writes 0)."""
    aov = scene.view_layers[0].aovs.add()
    aov.name, aov.type = "Backfacing", "VALUE"
    for material in _materials(scene):
        tree = material.node_tree
        geometry = tree.nodes.new("ShaderNodeNewGeometry")
        out = tree.nodes.new("ShaderNodeOutputAOV")
        out.aov_name = "Backfacing"
        tree.links.new(geometry.outputs["Backfacing"], out.inputs["Value"])


def main(jobs_path: str) -> None:
    import client_jobs

    client_jobs.run(client_jobs.load(jobs_path), render)
    client_jobs.finish()

if __name__ == "__main__":
    main(sys.argv[1])
