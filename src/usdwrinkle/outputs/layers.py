"""Bake the wrinkle fields into a USD layer: the per-vertex primvars the GPU computed.

The same engine computes a frame for a render and for a bake; the bake reads back
the fields of every wrinkled mesh. Layers are written atomically (a temporary file
beside the target, then a rename), and never over a layer the input stage uses.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from pxr import Sdf, UsdGeom, Vt

from .. import __version__
from ..images.colour import srgb_decode
from ..method.contract import COARSENING_MAX, MIN_RATIO
from ..process.errors import UsdWrinkleError
from ..usd import schema
from .atomic import atomic_path
from .sink import BakeScene

LAYER_FORMATS = (".usda", ".usdc", ".usd")

#: baked primvar -> (field, value type), from the one table (schema.BAKED_PRIMVARS)
_VALUE_TYPES = {1: Sdf.ValueTypeNames.FloatArray, 3: Sdf.ValueTypeNames.Vector3fArray}
PRIMVARS = {name: (field, _VALUE_TYPES[components])
            for name, (field, components) in schema.BAKED_PRIMVARS.items()
            if name not in schema.BAKED_SECOND_SYSTEM}
#: the second wave system, baked for meshes with wrinkle:biaxial on
SECOND_SYSTEM_PRIMVARS = {name: (field, _VALUE_TYPES[components])
                          for name, (field, components) in schema.BAKED_PRIMVARS.items()
                          if name in schema.BAKED_SECOND_SYSTEM}
DISPLAY_COLOR_FIELDS = ("amplitude", "compression")

# viridis at 9 stops: perceptually uniform, readable by colour-blind viewers
_VIRIDIS = np.array([
    [0.267, 0.005, 0.329], [0.283, 0.141, 0.458], [0.254, 0.265, 0.530],
    [0.207, 0.372, 0.553], [0.164, 0.471, 0.558], [0.128, 0.567, 0.551],
    [0.135, 0.659, 0.518], [0.267, 0.749, 0.441], [0.478, 0.821, 0.318],
    [0.741, 0.873, 0.150], [0.993, 0.906, 0.144]])


def viridis(values: np.ndarray) -> np.ndarray:
    """Map [0, 1] to viridis: sRGB stops, decoded to linear as displayColor expects."""
    t = np.clip(np.nan_to_num(np.asarray(values, np.float64)), 0, 1) * (len(_VIRIDIS) - 1)
    low = np.floor(t).astype(int).clip(0, len(_VIRIDIS) - 2)
    frac = (t - low)[:, None]
    rgb = _VIRIDIS[low] * (1 - frac) + _VIRIDIS[low + 1] * frac
    return srgb_decode(rgb).astype(np.float32)  # displayColor is linear


def _baked(fields, field: str) -> np.ndarray:
    """A baked primvar's values: the amplitudes as the surface draws them (a render from
    the bake draws the baked amplitudes as they are), every other field as computed."""
    if field == "amplitude":
        return fields.drawn_amplitude
    if field == "amplitude2":
        return fields.drawn_amplitude2
    return getattr(fields, field)


def display_values(field: str, fields: dict, params) -> np.ndarray:
    """The [0, 1] quantity shown by --display-color."""
    if field == "amplitude":  # over about the fold law's height of cloth crushed flat
        full = np.maximum(params.amplitude_scale * COARSENING_MAX * params.width / 4.0,
                          1e-30)
        return np.minimum(fields.drawn_amplitude / full, 1.0)
    return (1.0 - fields.compression) / (1.0 - MIN_RATIO)  # r in [MIN_RATIO, 1] -> [1, 0]


def check_layer_path(path: str) -> str:
    ext = os.path.splitext(path)[1].lower()
    if ext not in LAYER_FORMATS:
        raise UsdWrinkleError(f"unsupported layer format '{ext or path}': use .usda, .usdc or "
                              ".usd (a .usdz package cannot be edited in place)")
    return ext


def reanchored_copy(layer: Sdf.Layer, target: str, relative: bool = False) -> Sdf.Layer:
    """A copy of ``layer`` to be written at ``target``, its asset paths (sublayers,
    references, payloads, textures) rewritten so that they name the same files from
    there: each path anchored at ``layer`` is made relative to ``target``'s folder *as
    named* (USD anchors a relative path lexically, so a symlinked folder is taken as the
    user wrote it); a path inside a package keeps its ``[...]`` part
    ('../CesiumMan.usdz[0/img.jpg]'). Absolute paths stay absolute unless ``relative``
    (an anonymous paint layer's sublayer, written relative so the pair can move
    together); search paths that resolve nowhere are kept as written."""
    from pxr import UsdUtils

    def package_file(path: str) -> str:  # 'a.usdz[b/c.png]' -> 'a.usdz'
        return path[:path.index("[")] if path.endswith("]") and "[" in path else path

    folder = os.path.dirname(os.path.abspath(target))

    def move(asset: str) -> str:
        if not asset or asset.startswith("anon:"):
            return asset
        outer = package_file(asset)
        if os.path.isabs(outer) and not relative:
            return asset
        absolute = asset if os.path.isabs(outer) else layer.ComputeAbsolutePath(asset)
        disk = package_file(absolute)
        if not absolute or not os.path.isabs(disk):
            return asset  # a search path: resolved the same from anywhere
        moved = os.path.relpath(disk, folder)
        if not moved.startswith(("./", "../")):
            moved = "./" + moved
        return moved + absolute[len(disk):]

    copy = Sdf.Layer.CreateAnonymous(os.path.splitext(target)[1] or ".usda")
    copy.TransferContent(layer)
    UsdUtils.ModifyAssetPaths(copy, move)
    return copy


def _array(values: np.ndarray, type_name):
    values = np.ascontiguousarray(values, np.float32)
    if type_name in (Sdf.ValueTypeNames.FloatArray,):
        return Vt.FloatArray.FromNumpy(values)
    if type_name == Sdf.ValueTypeNames.Color3fArray:
        return Vt.Vec3fArray.FromNumpy(values)
    return Vt.Vec3fArray.FromNumpy(values)


@dataclass(frozen=True)
class LayerOptions:
    """What the primvar sink writes besides the wrinkle primvars.

    ``with_points``: also bake points and extent (all skinned meshes of the affected skel
    roots), and the normals where the mesh authors them, posed, in the attribute and with
    the interpolation it authors them with (``primvars:normals`` or ``normals``), as
    UsdSkelBakeSkinning does; each skinned mesh then binds no skeleton (``skel:skeleton``
    with no targets), so the composed stage is not skinned twice. Meshes without authored
    normals get none: renderers derive them from the points by the mesh's subdivision
    scheme, as usdwrinkle does. ``display_color``: a field shown as a viridis
    displayColor ramp. ``sparse``: the layer does not sublayer the input stage.
    ``frame_spec``: the frames as the user wrote them, recorded in the layer."""

    with_points: bool = False
    display_color: str | None = None
    sparse: bool = False
    frame_spec: str = ""


class LayerBaker:
    """The bake sink of the wrinkle primvars (outputs/sink.py): per frame, each wrinkled
    mesh's fields as vertex primvars; at the end, the layer's metadata."""

    def __init__(self, scene: BakeScene, options: LayerOptions):
        self.facts = scene.facts
        self.output = scene.output
        self.wrinkled = scene.meshes
        self.options = options
        self.layer: Sdf.Layer | None = None
        self.frames: list[float] = []
        self.point_meshes: dict = {}
        self.skel_roots: list[str] = []
        if options.with_points:
            self._collect_point_meshes(scene.records)
        self._specs: dict = {}

    def begin(self, layer: Sdf.Layer) -> None:
        self.layer = layer

    def commit(self) -> None:
        """Nothing beside the layer to move into place."""

    def release(self) -> None:
        """Nothing held."""

    def _collect_point_meshes(self, records: dict) -> None:
        roots = {root for path in self.wrinkled for root in self.facts.meshes[path].skel_roots}
        self.skel_roots = sorted(roots)
        for path, record in records.items():
            skinned_here = record.skin is not None and any(
                path.startswith(root + "/") for root in roots)
            if path in self.wrinkled or skinned_here:
                self.point_meshes[path] = record

    def _attr(self, prim_path: str, name: str, type_name, interpolation: str | None = None):
        key = (prim_path, name)
        spec = self._specs.get(key)
        if spec is None:
            prim_spec = self.layer.GetPrimAtPath(prim_path) or Sdf.CreatePrimInLayer(
                self.layer, prim_path)
            spec = attribute_spec(prim_spec, name, type_name, interpolation=interpolation)
            self._specs[key] = spec
        return spec.path

    def _set(self, attr_path, frame: float, value) -> None:
        set_value(self.layer, attr_path, frame, value)

    def add_frame(self, frame: float, fields: dict, resources: dict) -> None:
        """Record one frame: ``fields[path]`` (the wrinkled meshes'), the point meshes'
        points and posed shading normals read back through ``resources[path]``."""
        fields_by_path = dict(fields)
        for path in self.point_meshes:
            if path not in fields_by_path:
                fields_by_path[path] = resources[path].read_fields()
        for path, values_of in fields_by_path.items():
            for name, values in values_of.arrays().items():  # no NaN or Inf reaches a layer
                if isinstance(values, np.ndarray) and values.dtype.kind == "f" and \
                        not np.all(np.isfinite(values)):
                    raise UsdWrinkleError(
                        f"the computed {name} is not finite (NaN or Inf): the mesh's scale or "
                        "transform is out of the GPU's float range", path, None,
                        frame)
        self.frames.append(frame)
        for path, fields in fields_by_path.items():
            if path in self.wrinkled:
                primvars = dict(PRIMVARS)
                if self.wrinkled[path].params.biaxial > 0:
                    primvars.update(SECOND_SYSTEM_PRIMVARS)
                for name, (field, type_name) in primvars.items():
                    attr = self._attr(path, name, type_name, UsdGeom.Tokens.vertex)
                    self._set(attr, frame, _array(_baked(fields, field), type_name))
                if self.options.display_color:
                    colors = viridis(display_values(self.options.display_color, fields,
                                                    self.wrinkled[path].params))
                    attr = self._attr(path, "primvars:displayColor",
                                      Sdf.ValueTypeNames.Color3fArray, UsdGeom.Tokens.vertex)
                    self._set(attr, frame, Vt.Vec3fArray.FromNumpy(colors))
            if path in self.point_meshes:
                points = np.ascontiguousarray(fields.points, np.float32)
                self._set(self._attr(path, "points", Sdf.ValueTypeNames.Point3fArray), frame,
                          Vt.Vec3fArray.FromNumpy(points))
                if path in resources:
                    self._add_normals(path, frame, resources[path])
                extent = Vt.Vec3fArray.FromNumpy(
                    np.stack([points.min(0), points.max(0)]).astype(np.float32))
                self._set(self._attr(path, "extent", Sdf.ValueTypeNames.Float3Array), frame,
                          extent)

    def _display_color_material(self) -> None:
        """usdview (Storm) shows a mesh's bound material, which hides displayColor: each
        mesh given the ramp binds, for the preview purpose that Storm resolves first, a
        UsdPreviewSurface whose diffuseColor reads primvars:displayColor. Renderers of
        the full purpose keep the mesh's own material."""
        default = self.facts.default_prim_path
        root = Sdf.Path(default) if default else Sdf.Path.absoluteRootPath
        scope = root.AppendChild("WrinkleMaterials")
        path = scope.AppendChild("DisplayColor")
        scope_spec = Sdf.CreatePrimInLayer(self.layer, scope)
        if not scope_spec.typeName:
            scope_spec.specifier = Sdf.SpecifierDef
            scope_spec.typeName = "Scope"
        material = define_prim(self.layer, path, "Material")
        surface = define_prim(self.layer, path.AppendChild("PreviewSurface"), "Shader")
        attribute_spec(surface, "info:id", Sdf.ValueTypeNames.Token, "UsdPreviewSurface",
                       uniform=True)
        reader = define_prim(self.layer, path.AppendChild("DisplayColor"), "Shader")
        attribute_spec(reader, "info:id", Sdf.ValueTypeNames.Token,
                       "UsdPrimvarReader_float3", uniform=True)
        attribute_spec(reader, "inputs:varname", Sdf.ValueTypeNames.String, "displayColor")
        attribute_spec(reader, "inputs:fallback", Sdf.ValueTypeNames.Float3, (0.5, 0.5, 0.5))
        attribute_spec(reader, "outputs:result", Sdf.ValueTypeNames.Float3)
        attribute_spec(surface, "inputs:diffuseColor", Sdf.ValueTypeNames.Color3f,
                       connect=reader.path.AppendProperty("outputs:result"))
        attribute_spec(surface, "outputs:surface", Sdf.ValueTypeNames.Token)
        attribute_spec(material, "outputs:surface", Sdf.ValueTypeNames.Token,
                       connect=surface.path.AppendProperty("outputs:surface"))
        for mesh_path in self.wrinkled:
            bind_material(self.layer, mesh_path, path, purpose="preview")

    def _add_normals(self, path: str, frame: float, res) -> None:
        """The posed shading normals of a mesh that authors normals (read back through
        its resources), into the attribute it authors them in, with its interpolation;
        flattened, so an indexed primvar's indices are blocked."""
        plan = res.normal_plan
        if plan.source != "authored":
            return
        normals = res.read_shading_normals()
        if plan.indexed:  # the plan is the scene's reading of the mesh: no stage read here
            indices = self._attr(path, "primvars:normals:indices", Sdf.ValueTypeNames.IntArray)
            self.layer.GetAttributeAtPath(indices).default = Sdf.ValueBlock()
        attr = self._attr(path, plan.attribute, Sdf.ValueTypeNames.Normal3fArray,
                          plan.interpolation)
        self._set(attr, frame, Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(normals,
                                                                             np.float32)))

    def finish(self) -> dict:
        """The layer's metadata (time codes, up axis, units, default prim, the sublayered
        input), the display-colour material, and the skinned meshes' unbound skeletons;
        returns what customLayerData records of this bake."""
        output_path, options, facts = self.output, self.options, self.facts
        layer = self.layer
        layer.timeCodesPerSecond = facts.time_codes_per_second
        layer.framesPerSecond = facts.frames_per_second
        timed = [f for f in self.frames if f is not None]
        if timed:
            layer.startTimeCode = min(timed)
            layer.endTimeCode = max(timed)
        for key, value in facts.layer_info.items():
            layer.pseudoRoot.SetInfo(key, value)
        if facts.default_prim:
            layer.defaultPrim = facts.default_prim
        # the source stage as the layer's own paths are: relative to the layer's folder
        source_path = os.path.relpath(os.path.abspath(facts.path), os.path.dirname(
            os.path.abspath(output_path))).replace(os.sep, "/")
        if not options.sparse:
            # the layers the stage was composed with (--sublayer), stronger than it, and
            # its variant selections: the layer renders as the composed stage did
            for sublayer in getattr(facts, "sublayers", ()):
                layer.subLayerPaths.append(os.path.relpath(sublayer, os.path.dirname(
                    os.path.abspath(output_path))).replace(os.sep, "/"))
            layer.subLayerPaths.append(source_path)
            for prim_path, variant_set, name in getattr(facts, "variant_selections", ()):
                spec = Sdf.CreatePrimInLayer(layer, prim_path)
                spec.variantSelections[variant_set] = name
        if options.display_color and self.wrinkled:
            self._display_color_material()
        for path, record in self.point_meshes.items():
            if record.skin is None:
                continue
            # baked points are posed already: the mesh binds no skeleton any more, so
            # nothing skins it twice (UsdSkelBakeSkinning retypes the SkelRoot instead,
            # which leaves its bindings rootless: usdchecker's SkelBindingApiValidator)
            spec = self.layer.GetPrimAtPath(path) or Sdf.CreatePrimInLayer(self.layer, path)
            rel = spec.relationships.get("skel:skeleton") or Sdf.RelationshipSpec(
                spec, "skel:skeleton", custom=False)
            rel.targetPathList.ClearEditsAndMakeExplicit()
        shot_range = getattr(facts, "shot_range", None)
        return {"version": __version__, "frames": options.frame_spec, "source": source_path,
                "withPoints": options.with_points, "displayColor": options.display_color or "",
                "sparse": options.sparse,
                **({"shotStart": shot_range[0], "shotEnd": shot_range[1]}
                   if shot_range else {})}



def save_layer(layer: Sdf.Layer, output_path: str, metadata: dict, before_rename=None) -> None:
    """Record ``metadata`` as the layer's ``customLayerData["usdwrinkle"]`` and write the
    layer atomically; ``before_rename()`` runs once it is written under its temporary
    name (the wrinkle maps are moved into place there, so that an error leaves neither a
    layer naming missing maps nor maps without their layer)."""
    ext = check_layer_path(output_path)
    data = dict(layer.customLayerData)
    data["usdwrinkle"] = {**data.get("usdwrinkle", {}), **metadata}
    layer.customLayerData = data
    with atomic_path(output_path) as tmp:
        export_layer(layer, tmp, output_path, ext)
        if before_rename is not None:
            before_rename()


def new_layer() -> Sdf.Layer:
    """The anonymous layer a bake's sinks author into (save_layer writes it)."""
    return Sdf.Layer.CreateAnonymous(".usda")


def export_layer(layer: Sdf.Layer, tmp: str, output_path: str, ext: str | None = None) -> None:
    """Export ``layer`` to ``tmp`` (the temporary file of an atomic write of
    ``output_path``): the format from ``ext`` (``.usd`` is written as crate), and a
    failed write (a full disk, a read-only folder) as the one-line error with USD's
    reason, not the exception text USD repeats for every failed buffer."""
    from pxr import Tf

    from ..usd.diagnostics import usd_diagnostics, usd_error_text

    ext = ext or os.path.splitext(output_path)[1].lower()
    args = {"format": "usdc"} if ext == ".usd" else {}
    try:
        with usd_diagnostics() as messages:
            ok = layer.Export(tmp, args=args)
    except Tf.ErrorException as exc:
        reason = _first_write_error(str(exc)) or usd_error_text(exc)
        raise UsdWrinkleError(f"cannot write layer '{output_path}': {reason}") from None
    if not ok:
        detail = f": {messages[-1]}" if messages else ""
        raise UsdWrinkleError(f"cannot write layer '{output_path}'{detail}")


def _first_write_error(text: str) -> str | None:
    """The operating system's reason in USD's write errors ('No space left on device')."""
    import re

    match = re.search(r"Error occurred writing file: ([^'\n]+)", text)
    return match.group(1).strip() if match else None


def define_prim(layer: Sdf.Layer, path, type_name: str) -> Sdf.PrimSpec:
    """A ``def`` prim spec of ``type_name`` at ``path`` (its ancestors as ``over``s)."""
    spec = Sdf.CreatePrimInLayer(layer, path)
    spec.specifier = Sdf.SpecifierDef
    spec.typeName = type_name
    return spec


def attribute_spec(prim_spec: Sdf.PrimSpec, name: str, type_name, value=None, *,
                   uniform: bool = False, interpolation: str | None = None,
                   connect=None) -> Sdf.AttributeSpec:
    """The attribute spec ``name`` of ``prim_spec`` (made when missing; ``uniform``
    variability then), with its default ``value``, primvar ``interpolation`` and a
    connection to ``connect`` where given."""
    spec = prim_spec.attributes.get(name) or Sdf.AttributeSpec(
        prim_spec, name, type_name,
        Sdf.VariabilityUniform if uniform else Sdf.VariabilityVarying)
    if value is not None:
        spec.default = value
    if interpolation:
        spec.SetInfo("interpolation", interpolation)
    if connect is not None:
        spec.connectionPathList.explicitItems = [connect]
    return spec


def set_value(layer: Sdf.Layer, attr_path, frame: float | None, value) -> None:
    """A baked frame's value of the attribute at ``attr_path``: its time sample at
    ``frame``, or its default when the frame is the default time (None)."""
    if frame is None:
        layer.GetAttributeAtPath(attr_path).default = value
    else:
        layer.SetTimeSample(attr_path, frame, value)


def bind_material(layer: Sdf.Layer, prim_path, material_path, purpose: str = "") -> None:
    """Author a direct material binding of ``prim_path`` to ``material_path`` in
    ``layer`` (MaterialBindingAPI applied, ``material:binding`` targeting it, or
    ``material:binding:<purpose>``)."""
    spec = Sdf.CreatePrimInLayer(layer, prim_path)
    schemas = spec.GetInfo("apiSchemas") if spec.HasInfo("apiSchemas") else Sdf.TokenListOp()
    prepended = list(schemas.prependedItems)
    if "MaterialBindingAPI" not in prepended:
        schemas.prependedItems = prepended + ["MaterialBindingAPI"]
        spec.SetInfo("apiSchemas", schemas)
    name = f"material:binding:{purpose}" if purpose else "material:binding"
    rel = spec.relationships.get(name) or Sdf.RelationshipSpec(spec, name, custom=False)
    rel.targetPathList.explicitItems = [Sdf.Path(str(material_path))]
