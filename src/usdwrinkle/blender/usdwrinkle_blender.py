"""usdwrinkle's wrinkle materials in Blender (Cycles and EEVEE): a USD import hook.

A layer baked with ``usdwrinkle bake --maps normal,parallax`` holds, on each wrinkle
material, a MaterialX network (render context ``mtlx``) that bends the normals and moves
the look's textures with the folds, for any camera. Storm, Karma and other MaterialX
renderers draw it as it is. Blender's USD importer does not read MaterialX: without this
add-on it imports the universal UsdPreviewSurface (the wrinkle normal map of the first
baked frame, the texture unmoved).

With it, the importer hands each material whose ``outputs:mtlx:surface`` is a
``ND_UsdPreviewSurface_surfaceshader`` fed only by the nodes listed in ``NODES`` to this
hook, which builds the same network out of Blender shader nodes (UV Map, Image Texture,
Vector Math, Math, Geometry, Tangent, Principled BSDF):

- every MaterialX node becomes the Blender nodes that compute the same value; a 3x3
  matrix is kept as its three columns (Blender's shader nodes have no matrix socket);
- vectors in MaterialX's world space are the stage's: the importer turns a Y-up stage to
  Blender's Z-up, so the renderer's own world vectors (view direction, tangent frame) are
  turned back into the stage's axes, and the shading normal into Blender's;
- a time-sampled file (the maps of every baked frame) becomes an image sequence, so that
  the animation plays;
- the UsdPreviewSurface's inputs go to the Principled BSDF as Blender's importer maps
  them; its tangent-space normal is decoded with the same tangent frame.

**Dual-quaternion skinning.** Blender's importer gives every UsdSkel-skinned mesh an
Armature modifier with linear blending, whatever the mesh's ``skel:skinningMethod``
(bpy 5.0.1). A mesh that UsdSkel skins by dual quaternions (an elbow rigged to keep its
volume) then bends differently in Cycles than in usdview and usdwrinkle, and the baked
maps, which follow usdwrinkle's posed surface, land on another shape. After the import
this hook turns on the modifier's Preserve Volume for those meshes: Blender's dual
quaternions, which give UsdSkel's own baseline points (Pixar's ``dqs.baked.usda``) to
float precision (tests/test_realclients_blender.py).

A material the hook cannot build (a node it does not know, a file sequence whose frame
numbers are not its time codes) is left to the importer, which imports its
UsdPreviewSurface, and the reason is printed.

Install: Edit > Preferences > Add-ons > Install from Disk, pick this file
(``usdwrinkle blender-addon`` prints its path, or copies it with ``--copy DIR``), and
enable "usdwrinkle: wrinkle materials". Then File > Import > Universal Scene Description
(.usd*) as usual. In a script (``bpy`` as a module, or ``blender --background``)::

    import usdwrinkle_blender
    usdwrinkle_blender.register()
    bpy.ops.wm.usd_import(filepath="shot.maps.usda")

This file imports only Blender's ``bpy`` and the ``pxr`` that Blender bundles: it runs in
Blender's Python, where usdwrinkle itself is not installed.
"""
from __future__ import annotations

import os
import re

import bpy

if hasattr(bpy.utils, "expose_bundled_modules"):  # bpy as a module (Blender 4.4+)
    bpy.utils.expose_bundled_modules()

from pxr import Usd, UsdGeom, UsdShade, UsdSkel  # noqa: E402  (after Blender exposes its pxr)

bl_info = {
    "name": "usdwrinkle: wrinkle materials",
    "author": "usdwrinkle",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "File > Import > Universal Scene Description",
    "description": "Imports usdwrinkle's MaterialX wrinkle network (bent normals and the "
                   "texture moved with the folds) as Blender shader nodes, and skins "
                   "UsdSkel's dual-quaternion meshes as UsdSkel does",
    "category": "Import-Export",
}

#: the MaterialX render context whose surface output the hook reads
CONTEXT = "mtlx"
#: the surface shader it maps to a Principled BSDF
SURFACE_ID = "ND_UsdPreviewSurface_surfaceshader"
#: UsdPreviewSurface input -> Principled BSDF input (as Blender's importer maps them)
PRINCIPLED = {"diffuseColor": "Base Color", "emissiveColor": "Emission Color",
              "metallic": "Metallic", "roughness": "Roughness", "opacity": "Alpha",
              "ior": "IOR", "clearcoat": "Coat Weight", "clearcoatRoughness": "Coat Roughness"}
#: MaterialX address mode -> Image Texture extension
EXTENSION = {"periodic": "REPEAT", "clamp": "EXTEND", "mirror": "MIRROR", "constant": "CLIP"}
#: MaterialX colour spaces read as sRGB; any other file is read as data (Non-Color)
SRGB = {"srgb_texture", "sRGB", "srgb"}


class Unsupported(Exception):
    """The network holds something this hook does not build; the importer falls back."""


# --- the stage's axes against Blender's ---------------------------------------------

def _y_up(stage) -> bool:
    return UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y


class _Matrix:
    """A MaterialX matrix33 as its three columns (sockets or constants), or the inverse
    of such a matrix."""

    def __init__(self, columns, inverse=False):
        self.columns = columns
        self.inverse = inverse


class _Builder:
    """Blender nodes computing a MaterialX network's values, one per (node, output)."""

    def __init__(self, tree, stage, y_up: bool, import_context=None):
        self.tree = tree
        self.stage = stage
        self.y_up = y_up
        self.import_context = import_context
        self.values: dict = {}
        self.column = 0
        self.rows: dict = {}  # nodes placed so far in each column
        self._frame = None

    # -- node helpers ---------------------------------------------------------------
    def new(self, kind: str, **settings):
        node = self.tree.nodes.new(kind)
        for key, value in settings.items():
            setattr(node, key, value)
        # laid out right to left by depth from the surface, each column top to bottom, so
        # that the tree reads in the node editor
        row = self.rows.get(self.column, 0)
        self.rows[self.column] = row + 1
        node.location = (-220.0 * self.column, -170.0 * row)
        return node

    def feed(self, socket, value) -> None:
        """Connect ``value`` (an output socket or a constant) to ``socket``."""
        if isinstance(value, bpy.types.NodeSocket):
            self.tree.links.new(value, socket)
        elif isinstance(value, _Matrix):
            raise Unsupported("a matrix feeds a value input")
        elif isinstance(value, (int, float)):
            if hasattr(socket.default_value, "__len__"):
                socket.default_value = [float(value)] * len(socket.default_value)
            else:
                socket.default_value = float(value)
        else:
            values = [float(v) for v in value]
            size = len(socket.default_value)
            socket.default_value = (values + [0.0, 0.0, 0.0, 1.0][len(values):])[:size] \
                if size > len(values) else values[:size]

    def math(self, operation: str, a, b=0.0):
        node = self.new("ShaderNodeMath", operation=operation)
        self.feed(node.inputs[0], a)
        self.feed(node.inputs[1], b)
        return node.outputs[0]

    def vector(self, operation: str, a, b=None, scale=None):
        node = self.new("ShaderNodeVectorMath", operation=operation)
        self.feed(node.inputs[0], a)
        if b is not None:
            self.feed(node.inputs[1], b)
        if scale is not None:
            self.feed(node.inputs["Scale"], scale)
        return node.outputs["Value" if operation == "DOT_PRODUCT" else "Vector"]

    def combine(self, x, y, z=0.0):
        node = self.new("ShaderNodeCombineXYZ")
        for socket, value in zip(node.inputs[:3], (x, y, z), strict=True):
            self.feed(socket, value)
        return node.outputs[0]

    def separate(self, v):
        node = self.new("ShaderNodeSeparateXYZ")
        self.feed(node.inputs[0], v)
        return node.outputs

    def to_stage(self, v):
        """A vector in Blender's world axes, in the stage's: (x, y, z) -> (x, z, -y)
        for a Y-up stage (the importer turned it by +90 degrees about x)."""
        if not self.y_up:
            return v
        x, y, z = self.separate(v)
        return self.combine(x, z, self.math("MULTIPLY", y, -1.0))

    def to_blender(self, v):
        """A vector in the stage's world axes, in Blender's: (x, y, z) -> (x, -z, y)."""
        if not self.y_up:
            return v
        x, y, z = self.separate(v)
        return self.combine(x, self.math("MULTIPLY", z, -1.0), y)

    def geometry(self):
        if self._frame is None:
            self._frame = self.new("ShaderNodeNewGeometry")
        return self._frame

    # -- the network ----------------------------------------------------------------
    def value(self, shader_input: UsdShade.Input):
        """The value of a MaterialX input: a socket, a constant or a _Matrix."""
        sources = shader_input.GetConnectedSources()[0]
        if not sources:
            value = shader_input.Get()
            if value is None:
                raise Unsupported(f"{shader_input.GetAttr().GetPath()} has no value")
            return value
        source = sources[0]
        prim = source.source.GetPrim()
        if prim.IsA(UsdShade.Material):  # a material's interface input: its value
            attribute = _value_attribute(shader_input)
            if attribute.GetNumTimeSamples() > 0:
                raise Unsupported(f"{attribute.GetPath()} is animated (only a file may be)")
            value = attribute.Get()
            if value is None:
                raise Unsupported(f"{attribute.GetPath()} has no value")
            return value
        key = (prim.GetPath(), source.sourceName)
        if key not in self.values:
            self.values[key] = self.node(UsdShade.Shader(prim))
        return self.values[key]

    def inputs(self, shader: UsdShade.Shader) -> dict:
        return {i.GetBaseName(): i for i in shader.GetInputs()}

    def node(self, shader: UsdShade.Shader):
        node_id = str(shader.GetIdAttr().Get() or "")
        if not node_id.startswith("ND_"):
            raise Unsupported(f"{shader.GetPath()} is not a MaterialX node ({node_id!r})")
        kind = node_id[3:]
        inputs = self.inputs(shader)
        self.column += 1
        try:
            return self._node(kind, inputs, shader)
        finally:
            self.column -= 1

    def _arg(self, inputs, name):
        if name not in inputs:
            raise Unsupported(f"input {name} is missing")
        return self.value(inputs[name])

    def _node(self, kind: str, inputs: dict, shader):
        arg = lambda name: self._arg(inputs, name)  # noqa: E731
        op, _, signature = kind.partition("_")
        float_op = signature in ("float", "float_FA")
        vector_op = signature in ("vector2", "vector3", "color3", "vector3FA", "vector2FA",
                                  "color3FA")
        if op == "geompropvalue" and signature == "vector2":
            node = self.new("ShaderNodeUVMap", uv_map=str(arg("geomprop")))
            return node.outputs["UV"]
        if op == "image" and signature in ("vector3", "color3", "float"):
            return self.image(inputs, signature, shader)
        if op == "viewdirection" and signature == "vector3":
            self.world_space(inputs)
            return self.to_stage(self.vector("SCALE", self.geometry().outputs["Incoming"],
                                             scale=-1.0))
        if op in ("tangent", "bitangent", "normal") and signature == "vector3":
            self.world_space(inputs)
            return self.frame_axis(op)
        if op == "dotproduct" and signature == "vector3":
            return self.vector("DOT_PRODUCT", arg("in1"), arg("in2"))
        if op == "crossproduct" and signature == "vector3":
            return self.vector("CROSS_PRODUCT", arg("in1"), arg("in2"))
        if op == "normalize" and signature == "vector3":
            return self.vector("NORMALIZE", arg("in"))
        if op == "absval" and float_op:
            return self.math("ABSOLUTE", arg("in"))
        if op in ("max", "min", "add", "subtract", "multiply", "divide") and float_op:
            operation = {"max": "MAXIMUM", "min": "MINIMUM"}.get(op, op.upper())
            return self.math(operation, arg("in1"), arg("in2"))
        if op in ("add", "subtract", "multiply", "divide") and vector_op:
            if signature.endswith("FA"):  # a vector and a float
                factor = arg("in2")
                if op == "divide":
                    factor = self.math("DIVIDE", 1.0, factor)
                if op in ("multiply", "divide"):
                    return self.vector("SCALE", arg("in1"), scale=factor)
                factor = self.combine(factor, factor, factor)
                return self.vector(op.upper(), arg("in1"), factor)
            return self.vector(op.upper(), arg("in1"), arg("in2"))
        if op in ("combine2", "combine3") and signature in ("vector2", "vector3", "color3"):
            return self.combine(*(arg(f"in{i}") for i in range(1, int(op[-1]) + 1)))
        if op == "ifgreatereq" and signature in ("vector3", "float"):
            # value1 >= value2 ? in1 : in2, blended by an exact 0 or 1
            chosen = self.math("SUBTRACT", 1.0, self.math("LESS_THAN", arg("value1"),
                                                           arg("value2")))
            if signature == "float":
                return self.math("ADD", arg("in2"), self.math(
                    "MULTIPLY", self.math("SUBTRACT", arg("in1"), arg("in2")), chosen))
            other = arg("in2")
            step = self.vector("SUBTRACT", arg("in1"), other)
            return self.vector("ADD", other, self.vector("SCALE", step, scale=chosen))
        if op == "creatematrix" and signature == "vector3_matrix33":
            return _Matrix([arg("in1"), arg("in2"), arg("in3")])
        if op == "invertmatrix" and signature == "matrix33":
            matrix = arg("in")
            if not isinstance(matrix, _Matrix):
                raise Unsupported("a constant matrix")
            return _Matrix(matrix.columns, not matrix.inverse)
        if op == "transformmatrix" and signature == "vector3":
            matrix = arg("mat")
            if not isinstance(matrix, _Matrix):
                raise Unsupported("a constant matrix")
            return self.transform(matrix, arg("in"))
        if kind == "UsdPreviewSurface_surfaceshader":
            return self.surface(inputs)
        raise Unsupported(f"{shader.GetPath()}: no Blender nodes for ND_{kind}")

    def world_space(self, inputs) -> None:
        space = inputs.get("space")
        if space is not None and space.Get() not in (None, "world"):
            raise Unsupported(f"space {space.Get()!r} (only world space is built)")

    def frame_axis(self, axis: str):
        """The renderer's tangent frame in the stage's axes: the UV tangent, the shading
        normal and N x T (any frame with N serves: the network's normal is expressed in
        it and decoded with it)."""
        if axis not in self.values:  # each axis's nodes are made once
            if axis == "normal":
                made = self.to_stage(self.geometry().outputs["Normal"])
            elif axis == "tangent":
                node = self.new("ShaderNodeTangent", direction_type="UV_MAP")
                made = self.to_stage(node.outputs["Tangent"])
            else:
                made = self.vector("CROSS_PRODUCT", self.frame_axis("normal"),
                                   self.frame_axis("tangent"))
            self.values[axis] = made
        return self.values[axis]

    def transform(self, matrix: _Matrix, v):
        """``matrix`` times ``v`` (MaterialX's mat * in: the columns weighted by v); for an
        inverse, by Cramer's rule: (v.(b x c), v.(c x a), v.(a x b)) / a.(b x c)."""
        a, b, c = matrix.columns
        if not matrix.inverse:
            x, y, z = self.separate(v)
            out = self.vector("SCALE", a, scale=x)
            out = self.vector("ADD", out, self.vector("SCALE", b, scale=y))
            return self.vector("ADD", out, self.vector("SCALE", c, scale=z))
        bc = self.vector("CROSS_PRODUCT", b, c)
        ca = self.vector("CROSS_PRODUCT", c, a)
        ab = self.vector("CROSS_PRODUCT", a, b)
        det = self.vector("DOT_PRODUCT", a, bc)
        rows = [self.vector("DOT_PRODUCT", v, axis) for axis in (bc, ca, ab)]
        return self.vector("SCALE", self.combine(*rows), scale=self.math("DIVIDE", 1.0, det))

    def decode(self, tangent_normal):
        """UsdPreviewSurface's tangent-space normal in world space: T x + B y + N z with
        the renderer's frame (MaterialX's normalmap), normalised, in Blender's axes."""
        frame = [self.frame_axis(a) for a in ("tangent", "bitangent", "normal")]
        world = self.transform(_Matrix(frame), tangent_normal)
        return self.to_blender(self.vector("NORMALIZE", world))

    # -- images -----------------------------------------------------------------------
    def image(self, inputs, signature: str, shader):
        file_input = inputs.get("file")
        if file_input is None:
            raise Unsupported(f"{shader.GetPath()} has no file")
        attribute = _value_attribute(file_input)
        node = self.new("ShaderNodeTexImage", interpolation="Linear")
        node.extension = EXTENSION.get(str(_value(inputs, "uaddressmode", "periodic")),
                                       "REPEAT")
        colour_space = attribute.GetColorSpace() if attribute.HasColorSpace() else ""
        srgb = signature == "color3" and colour_space in SRGB
        _load(node, attribute, self.import_context, srgb)
        if "texcoord" in inputs:
            self.feed(node.inputs["Vector"], self.value(inputs["texcoord"]))
        if signature == "float":
            return self.separate(node.outputs["Color"])[0]
        return node.outputs["Color"]

    # -- the surface ------------------------------------------------------------------
    def surface(self, inputs):
        bsdf = self.new("ShaderNodeBsdfPrincipled")
        for name, target in PRINCIPLED.items():
            if name in inputs:
                self.feed(bsdf.inputs[target], self.value(inputs[name]))
        if "emissiveColor" in inputs:
            bsdf.inputs["Emission Strength"].default_value = 1.0
        if "normal" in inputs:
            self.feed(bsdf.inputs["Normal"], self.decode(self.value(inputs["normal"])))
        return bsdf.outputs["BSDF"]


def _value(inputs, name, default):
    shader_input = inputs.get(name)
    value = shader_input.Get() if shader_input is not None else None
    return default if value is None else value


def _value_attribute(shader_input: UsdShade.Input):
    """The attribute that gives ``shader_input`` its value (a material input it is
    connected to, or itself)."""
    attributes = shader_input.GetValueProducingAttributes()
    if not attributes:
        raise Unsupported(f"{shader_input.GetAttr().GetPath()} has no value")
    return attributes[0]


_DIGITS = re.compile(r"(\d+)(\.[^./\\]+)$")


def _load(node, attribute, import_context, srgb: bool) -> None:
    """The Image Texture ``node`` reads ``attribute``'s file: a still image, or, when it
    is time-sampled, the sequence of files whose frame numbers are the time codes."""
    temporary = []

    def local(asset):
        path = asset.resolvedPath or asset.path
        if import_context is not None and hasattr(import_context, "import_texture"):
            # a texture inside a .usdz comes out as a file (maybe a temporary one)
            copied, is_temporary = import_context.import_texture(path)
            if copied:
                path = copied
                if is_temporary:
                    temporary.append(path)
        return path

    times = attribute.GetTimeSamples()
    paths = [local(attribute.Get(t)) for t in times] if times else \
        [local(attribute.Get())]
    for path in paths:
        if not path or not os.path.isfile(path):
            raise Unsupported(f"{attribute.GetPath()}: no file {path!r}")
    image = bpy.data.images.load(paths[0], check_existing=True)
    image.colorspace_settings.name = "sRGB" if srgb else "Non-Color"
    node.image = image
    if len(paths) == 1:
        if temporary:  # the importer's temporary copy goes away: keep the pixels
            image.pack()
        return
    numbers = []
    for time, path in zip(times, paths, strict=True):
        match = _DIGITS.search(os.path.basename(path))
        if match is None or float(time) != round(time) or int(match.group(1)) != round(time) \
                or _DIGITS.sub("", path) != _DIGITS.sub("", paths[0]):
            raise Unsupported(f"{attribute.GetPath()}: {os.path.basename(path)} at time "
                              f"{time:g} is not a frame-numbered sequence")
        numbers.append(int(match.group(1)))
    first, last = min(numbers), max(numbers)
    if last - first + 1 != len(numbers):
        raise Unsupported(f"{attribute.GetPath()}: frames {first}-{last} have gaps")
    image.source = "SEQUENCE"
    user = node.image_user
    user.frame_start = first           # Blender reads file number (frame - start + 1) + offset
    user.frame_offset = first - 1
    user.frame_duration = len(numbers)
    user.use_auto_refresh = True


def _surface_shader(usd_material):
    output = usd_material.GetSurfaceOutput(CONTEXT)
    if not output or not output.HasConnectedSource():
        return None
    shader = UsdShade.Shader(output.GetConnectedSources()[0][0].source.GetPrim())
    return shader if shader.GetIdAttr().Get() == SURFACE_ID else None


def build(import_context, bl_material, usd_material) -> bool:
    """Build ``usd_material``'s MaterialX network into ``bl_material`` (an empty node
    tree); raises Unsupported, leaving the tree empty, when it cannot."""
    shader = _surface_shader(usd_material)
    if shader is None:
        raise Unsupported(f"{usd_material.GetPath()} has no {SURFACE_ID} in {CONTEXT}")
    bl_material.use_nodes = True
    tree = bl_material.node_tree
    stage = usd_material.GetPrim().GetStage()
    builder = _Builder(tree, stage, _y_up(stage), import_context)
    try:
        bsdf = builder.node(shader)
        output = tree.nodes.new("ShaderNodeOutputMaterial")
        output.location = (300.0, 0.0)
        tree.links.new(bsdf, output.inputs["Surface"])
    except Exception:
        tree.nodes.clear()
        raise
    return True


def _check(usd_material) -> None:
    """Raises Unsupported when the network holds a node this hook does not build (the
    same walk as build(), on a scratch material)."""
    scratch = bpy.data.materials.new("usdwrinkle_poll")
    try:
        build(None, scratch, usd_material)
    finally:
        bpy.data.materials.remove(scratch)


def skinning_methods(stage) -> dict:
    """{mesh path: UsdSkel's skinning method} for every mesh a skeleton binding skins
    (the method as UsdSkel resolves it: ``primvars:skel:skinningMethod``, inherited)."""
    cache = UsdSkel.Cache()
    methods = {}
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if not prim.IsA(UsdSkel.Root):
            continue
        root = UsdSkel.Root(prim)
        cache.Populate(root, Usd.TraverseInstanceProxies())
        for binding in cache.ComputeSkelBindings(root, Usd.TraverseInstanceProxies()):
            for target in binding.GetSkinningTargets():
                methods[target.GetPrim().GetPath()] = str(target.GetSkinningMethod() or
                                                          "classicLinear")
    return methods


def preserve_volume(import_context) -> list[str]:
    """Turns on Preserve Volume (Blender's dual quaternions) on the Armature modifiers of
    the imported objects whose mesh UsdSkel skins by dual quaternions; returns their
    names."""
    methods = skinning_methods(import_context.get_stage())
    duals = sorted(str(path) for path, method in methods.items() if method == "dualQuaternion")
    if duals and not hasattr(import_context, "get_prim_map"):
        print(f"usdwrinkle: this Blender gives import hooks no prim map; {', '.join(duals)} "
              f"stay skinned linearly (tick Preserve Volume on their Armature modifiers)")
        return []
    turned = []
    for path, imported in import_context.get_prim_map().items():
        if methods.get(path) != "dualQuaternion":
            continue
        for owner in imported:
            if not isinstance(owner, bpy.types.Object):
                continue
            for modifier in owner.modifiers:
                if modifier.type == "ARMATURE" and not modifier.use_deform_preserve_volume:
                    modifier.use_deform_preserve_volume = True
                    turned.append(owner.name)
    if turned:
        print(f"usdwrinkle: dual-quaternion skinning (Preserve Volume) on "
              f"{', '.join(sorted(set(turned)))}")
    return turned


class USDWrinkleHook(bpy.types.USDHook):
    """Imports usdwrinkle's MaterialX wrinkle networks as Blender shader nodes, and skins
    UsdSkel's dual-quaternion meshes by Blender's dual quaternions."""

    bl_idname = "usdwrinkle_materials"
    bl_label = "usdwrinkle wrinkle materials"
    bl_description = "usdwrinkle's bent normals and texture deformation (MaterialX) " \
                     "as Blender shader nodes; UsdSkel's dual-quaternion skinning"

    @staticmethod
    def material_import_poll(import_context, usd_material):
        if _surface_shader(usd_material) is None:
            return False
        try:
            _check(usd_material)
        except Unsupported as error:
            print(f"usdwrinkle: {usd_material.GetPath()}: the UsdPreviewSurface is "
                  f"imported instead ({error})")
            return False
        return True

    @staticmethod
    def on_material_import(import_context, bl_material, usd_material):
        return build(import_context, bl_material, usd_material)

    @staticmethod
    def on_import(import_context):
        preserve_volume(import_context)
        return True


def register():
    bpy.utils.register_class(USDWrinkleHook)


def unregister():
    bpy.utils.unregister_class(USDWrinkleHook)


__all__ = ["USDWrinkleHook", "Unsupported", "build", "preserve_volume", "register",
           "skinning_methods", "unregister"]
