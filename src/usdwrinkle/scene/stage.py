"""The scene delegate: a Usd.Stage in, frozen numpy records out.

:class:`StageSceneDelegate` converts once, at this boundary. Per mesh it keeps a
:class:`MeshRecord` (topology, rest pose, skinning, parameters, material); per
frame it produces a :class:`FrameRecord` (posing inputs, transforms, camera,
lights). Nothing downstream sees a Usd object.
"""
from __future__ import annotations

import dataclasses
import logging
import math
import os
from collections import OrderedDict

import numpy as np
from pxr import Sdf, Tf, Usd, UsdGeom, UsdShade, UsdSkel

from ..process.errors import UsdWrinkleError
from ..process.limits import MAX_FRAMES, MAX_POINTS, MAX_TIME_CODE
from ..usd import schema
from ..usd.diagnostics import usd_diagnostics, usd_error_text
from ..usd.values import (
    require_mesh_array,
    static_flattened,
    static_value,
)
from .baked import BakedSource, find_baked
from .changes import ChangeTracker
from .dirty import DirtyBits, classify
from .inputs import StageInputs, package_file, scan_inputs
from .material import read_material
from .normals import plan_normals
from .params import read_params
from .records import FrameRecord, MeshFrame, MeshRecord
from .sampling import RENDERED_PURPOSES, FrameSampler, finite_points
from .skel import SkelBindings, skin_data
from .topology import Topology, build_topology, vertex_normals

_log = logging.getLogger(__name__)

#: prims whose edits change the skinning of the meshes bound to them
SKEL_TYPES = (UsdSkel.Root, UsdSkel.Skeleton, UsdSkel.Animation, UsdSkel.BlendShape)
#: prims whose edits change the materials of the meshes bound to them
SHADING_TYPES = (UsdShade.Material, UsdShade.NodeGraph, UsdShade.Shader)


def _is_a(prim: Usd.Prim, types) -> bool:
    return bool(prim) and any(prim.IsA(kind) for kind in types)


#: root layer identifier -> the StageInputs of stages opened by open_stage, the most
#: recent INPUTS_KEPT (a long-running host such as usdview opens many stages; an evicted
#: entry is scanned again when asked for)
_INPUTS: OrderedDict[str, StageInputs] = OrderedDict()
INPUTS_KEPT = 16


def _keep_inputs(identifier: str, inputs: StageInputs) -> None:
    _INPUTS[identifier] = inputs
    _INPUTS.move_to_end(identifier)
    while len(_INPUTS) > INPUTS_KEPT:
        _INPUTS.popitem(last=False)


def open_stage(path: str, composition=None) -> Usd.Stage:
    """Open a stage with one-line errors: a missing file, one that is not a regular file
    (anywhere in its layers and textures), an unreadable or malformed layer (with its
    file:line). USD's warnings while opening are logged, one line each. ``composition``
    (scene/composition.Composition): sublayers over it, variant selections and a
    population mask, in an anonymous session layer."""
    if not os.path.exists(path):
        raise UsdWrinkleError(f"stage file '{path}' does not exist")
    inputs = scan_inputs(path)
    root = inputs.layers[0]
    session = mask = None
    if composition:
        from .composition import population_mask, session_layer

        session = session_layer(composition, path)
        mask = population_mask(composition)
        for sublayer in session.subLayerPaths:  # also what the sublayers read
            extra = scan_inputs(sublayer)
            inputs.files |= extra.files
            inputs.inodes |= extra.inodes
            inputs.missing |= extra.missing
    try:
        with usd_diagnostics(forward=True):
            if mask is not None:
                stage = Usd.Stage.OpenMasked(root, session, mask) if session is not None \
                    else Usd.Stage.OpenMasked(root, mask)
            elif session is not None:
                stage = Usd.Stage.Open(root, session)
            else:
                stage = Usd.Stage.Open(root)
    except Tf.ErrorException as exc:
        raise UsdWrinkleError(f"cannot open '{path}' as a USD stage: "
                              f"{usd_error_text(exc)}") from None
    if stage is None:
        raise UsdWrinkleError(f"cannot open '{path}' as a USD stage")
    if composition:
        from .composition import check_composed

        check_composed(stage, composition)
    inputs.layers = []  # the stage holds what it uses; a cache must not keep stale layers
    _keep_inputs(root.identifier, inputs)
    return stage


def stage_inputs(stage: Usd.Stage) -> StageInputs:
    """Every file the stage reads (scene/inputs.py), for output checks."""
    root = stage.GetRootLayer()
    inputs = _INPUTS.get(root.identifier)
    if inputs is None:
        inputs = scan_inputs(root.realPath) if root.realPath and \
            "[" not in root.realPath else StageInputs()
    _keep_inputs(root.identifier, inputs)
    inputs.layers = []
    for layer in stage.GetUsedLayers():  # also what a session layer brought in
        if layer.realPath:
            inputs.add_file(package_file(layer.realPath))
    return inputs


def rest_pose(prim: Usd.Prim, skinned: bool = False):
    """The rest pose of a mesh: (point_cached, rest points value, attribute it came from).

    UsdSkel meshes rest in their authored points. Other meshes are point caches when
    their points are time-sampled or ``primvars:rest`` is authored; their rest pose is
    ``primvars:rest`` when authored, else the default-time points, else the first sample.
    """
    path = str(prim.GetPath())
    points_attr = UsdGeom.Mesh(prim).GetPointsAttr()
    rest_primvar = UsdGeom.PrimvarsAPI(prim).GetPrimvar("rest")
    require_mesh_array(points_attr, path)
    if rest_primvar:
        require_mesh_array(rest_primvar.GetAttr(), path)
    has_rest = not skinned and bool(rest_primvar) and rest_primvar.HasAuthoredValue()
    point_cached = not skinned and (points_attr.GetNumTimeSamples() > 0 or has_rest)
    if has_rest:
        return point_cached, static_flattened(rest_primvar), "primvars:rest"
    return point_cached, static_value(points_attr), "points"


def outside_range_note(stage: Usd.Stage, frames: list[float | None]) -> str | None:
    """A warning when --frames asks for frames outside the stage's authored time range:
    they hold the animation's last (or first) pose, and the phase history runs from the
    start up to them (a long preroll). None when every frame lies inside, or the stage
    has no range."""
    finite = [f for f in frames if f is not None]
    if not finite or not stage.HasAuthoredTimeCodeRange():
        return None
    start, end = stage.GetStartTimeCode(), stage.GetEndTimeCode()
    outside = [f for f in finite if f < start or f > end]
    if not outside:
        return None
    from ..process.timecode import format_frame

    return (f"{len(outside)} of the {len(finite)} frame(s) lie outside the stage's time range "
            f"{format_frame(start)}..{format_frame(end)} (first: {format_frame(outside[0])}): "
            "they show the animation held at its ends, and the phase history is computed "
            f"from frame {format_frame(start)} up to them (pass `history_start` to begin it "
            "elsewhere)")


def stage_frames(stage: Usd.Stage) -> list[float | None]:
    """The stage's authored start..end frames (step 1), or [None] for the default time.

    A range that is not finite, runs backwards, lies beyond +-MAX_TIME_CODE or holds more
    than MAX_FRAMES frames is refused, naming the layer's metadata.
    """
    span = stage_span(stage)
    if span is None:
        return [None]
    return [float(f) for f in np.arange(span[0], span[1] + 0.5)]


def stage_span(stage: Usd.Stage) -> tuple[float, float] | None:
    """The stage's authored (start, end) frames, checked as stage_frames says, or None
    for the default time (without building the list of frames: the phase history asks
    for its start at every frame)."""
    if not stage.HasAuthoredTimeCodeRange():
        return None
    start, end = stage.GetStartTimeCode(), stage.GetEndTimeCode()
    if math.isfinite(start) and math.isfinite(end) and \
            max(abs(start), abs(end)) <= MAX_TIME_CODE and start <= end and \
            end - start + 1 <= MAX_FRAMES:
        return start, end
    where = f"startTimeCode {start:g}, endTimeCode {end:g} of '{stage.GetRootLayer().identifier}'"
    if not (math.isfinite(start) and math.isfinite(end)) or max(abs(start), abs(end)) > \
            MAX_TIME_CODE:
        raise UsdWrinkleError(f"the stage's frame range is not finite within "
                              f"+-{MAX_TIME_CODE:g} ({where})")
    if end < start:
        raise UsdWrinkleError(f"the stage's endTimeCode is before its startTimeCode ({where}); "
                              "fix the metadata or pass `frames`")
    if end - start + 1 > MAX_FRAMES:
        raise UsdWrinkleError(f"the stage's frame range holds more than {MAX_FRAMES:,} frames "
                              f"({where}); pass `frames`")
    raise AssertionError("unreachable")  # every failed condition above raised


def inherited_range_note(stage: Usd.Stage) -> str | None:
    """When the root layer authors no time range but a layer under it does (a shot that
    sublayers an animated asset: USD takes the range from the root layer alone), a note
    that says the default time is rendered and which --frames would give the asset's."""
    if stage.HasAuthoredTimeCodeRange():
        return None
    for layer in stage.GetLayerStack(includeSessionLayers=False)[1:]:
        if layer.HasStartTimeCode() and layer.HasEndTimeCode():
            start, end = layer.startTimeCode, layer.endTimeCode
            if math.isfinite(start) and math.isfinite(end) and end >= start:
                return (f"the stage's root layer authors no startTimeCode/endTimeCode, so only "
                        f"the default time is processed; its sublayer "
                        f"'{os.path.basename(layer.identifier)}' spans {start:g}..{end:g} "
                        f"(pass `frames` {start:g}:{end:g}, or author the range on the root "
                        "layer)")
    return None


def read_faces(prim: Usd.Prim):
    """(faceVertexCounts, faceVertexIndices, holeIndices or None, left-handed) of a mesh,
    read by the static rule (time-sampled topology at its first sample); counts and
    indices are None when it has no faces."""
    mesh = UsdGeom.Mesh(prim)
    path = str(prim.GetPath())
    require_mesh_array(mesh.GetFaceVertexCountsAttr(), path)
    require_mesh_array(mesh.GetFaceVertexIndicesAttr(), path)
    counts = static_value(mesh.GetFaceVertexCountsAttr())
    indices = static_value(mesh.GetFaceVertexIndicesAttr())
    holes = static_value(mesh.GetHoleIndicesAttr())
    left_handed = static_value(mesh.GetOrientationAttr()) == UsdGeom.Tokens.leftHanded
    if counts is None or indices is None or len(counts) == 0:
        return None, None, None, left_handed
    return (np.asarray(counts), np.asarray(indices),
            None if holes is None else np.asarray(holes), left_handed)


def read_topology(prim: Usd.Prim, rest: np.ndarray, faces=None) -> Topology | None:
    """Triangulated topology of a mesh (None without faces); ``faces``: read_faces'."""
    counts, indices, holes, left_handed = faces or read_faces(prim)
    if counts is None:
        return None
    topology = build_topology(counts, indices, rest, holes, str(prim.GetPath()))
    if left_handed:
        # Flip the triangles' winding, not the faces, so faceVarying corners still map.
        topology = dataclasses.replace(
            topology, triangles=np.ascontiguousarray(topology.triangles[:, [0, 2, 1]]),
            corner_face_vertex=np.ascontiguousarray(topology.corner_face_vertex[:, [0, 2, 1]]))
    return topology


class StageSceneDelegate:
    """Reads a stage for the render delegate.

    Parameters
    ----------
    stage : Usd.Stage or str
    all_meshes : bool
        Treat every Mesh as if WrinkleAPI were applied (with fallbacks).
    relax_iterations : int or None
        Override every mesh's ``wrinkle:relaxIterations``.
    use_baked : bool
        Read the baked wave fields of meshes that hold them (scene/baked.py); such a mesh
        is wrinkled even without WrinkleAPI. False (``--recompute``, and the bake itself)
        ignores them.
    """

    def __init__(self, stage, all_meshes: bool = False, relax_iterations: int | None = None,
                 use_baked: bool = True):
        self.stage = open_stage(stage) if isinstance(stage, (str, os.PathLike)) else stage
        self.all_meshes = all_meshes
        self.use_baked = use_baked
        #: mesh path -> its baked wave fields
        self.baked: dict[str, BakedSource] = {}
        self.up_axis = UsdGeom.GetStageUpAxis(self.stage)
        self.skel = SkelBindings(self.stage)
        self._relax_override = relax_iterations
        self._prims: dict[str, Usd.Prim] = {}
        #: per frame: the meshes, the camera and the lights (scene/sampling.py)
        self.sampler = FrameSampler(self)
        self.meshes: dict[str, MeshRecord] = {}
        #: gprims a render leaves out: not Mesh prims (Sphere, Cube, BasisCurves, ...)
        self.undrawn: list[tuple[str, str]] = []
        for prim in self._rendered_gprims(self.stage.GetPseudoRoot()):
            if prim.IsA(UsdGeom.Mesh):
                self._add_mesh(prim)
            else:
                self.undrawn.append((str(prim.GetPath()), prim.GetTypeName()))
        if self.undrawn:
            shown = ", ".join(f"{path} ({kind})" for path, kind in self.undrawn[:4])
            more = f" and {len(self.undrawn) - 4} more" if len(self.undrawn) > 4 else ""
            _log.warning(f"{len(self.undrawn)} gprim(s) are not drawn: usdwrinkle draws Mesh "
                         f"prims only ({shown}{more}); convert them to meshes to see them")
        #: edits of the stage from now on (process_changes)
        self.tracker = ChangeTracker(self.stage)

    @staticmethod
    def _rendered_meshes(root: Usd.Prim):
        """The Mesh prims at or under ``root`` that a render draws (purpose default or
        render), instance proxies included."""
        for prim in StageSceneDelegate._rendered_gprims(root):
            if prim.IsA(UsdGeom.Mesh):
                yield prim

    @staticmethod
    def _rendered_gprims(root: Usd.Prim):
        """The gprims at or under ``root`` of purpose default or render, instance proxies
        included (a render draws the Mesh prims among them)."""
        for prim in Usd.PrimRange(root, Usd.TraverseInstanceProxies()):
            if prim.IsA(UsdGeom.Gprim) and \
                    UsdGeom.Imageable(prim).ComputePurpose() in RENDERED_PURPOSES:
                yield prim

    def _add_mesh(self, prim: Usd.Prim) -> bool:
        path = str(prim.GetPath())
        self._forget(path)
        record = self._mesh_record(prim, self._relax_override)
        if record is None:
            return False
        self.meshes[path] = record
        self._prims[path] = prim
        return True

    def _forget(self, path: str) -> None:
        self.meshes.pop(path, None)
        self._prims.pop(path, None)
        self.baked.pop(path, None)

    def _wrinkle_source(self, prim: Usd.Prim, num_points: int):
        """(baked fields or None, wrinkled?) of a mesh; the baked fields are registered."""
        path = str(prim.GetPath())
        baked = find_baked(prim, num_points) if self.use_baked else None
        self.baked.pop(path, None)
        if baked is not None:
            self.baked[path] = baked
        return baked, self.all_meshes or schema.has_wrinkle_api(prim) or baked is not None

    # -- change tracking ---------------------------------------------------------------
    def process_changes(self) -> tuple[dict[str, int], list[str], list[str]]:
        """Bring the records up to date with the stage's edits since the last call.

        Returns ({mesh path: dirty bits}, added mesh paths, removed mesh paths). Only
        what an edit touches is read again: a wrinkle parameter re-reads the parameters,
        a material the material, topology (faces, rest pose, skinning) the whole mesh;
        an edit elsewhere (a light, a camera, an unrelated prim) dirties no mesh.
        """
        resynced, changed = self.tracker.take()
        bits: dict[str, int] = {}
        if not resynced and not changed:
            return bits, [], []

        def mark(path: str, value: int) -> None:
            if value:
                bits[path] = bits.get(path, DirtyBits.CLEAN) | value

        before = set(self.meshes)
        rebuild_skel = shading = False
        structural: set[str] = set()
        for path in resynced | changed:
            prim_path = path.GetPrimPath()
            prim = self.stage.GetPrimAtPath(prim_path)
            if not path.IsPropertyPath():
                structural.add(str(prim_path))  # a prim added, removed or re-composed
            elif str(prim_path) in self.meshes:
                mark(str(prim_path), classify(path.name))
                if path.name == "purpose":
                    structural.add(str(prim_path))
            elif _is_a(prim, SKEL_TYPES):
                rebuild_skel = True
            elif _is_a(prim, SHADING_TYPES):
                shading = True
            elif path.name in ("visibility", "purpose") or path.name.startswith("xformOp"):
                # an ancestor's transform or visibility: sampled per frame; purpose decides
                # which meshes are drawn
                if path.name == "purpose":
                    structural.add(str(prim_path))
                for mesh in self.meshes:
                    if Sdf.Path(mesh).HasPrefix(prim_path):
                        mark(mesh, classify(path.name))
        for root in structural:
            prim = self.stage.GetPrimAtPath(root)
            rebuild_skel = rebuild_skel or _is_a(prim, SKEL_TYPES)
            shading = shading or _is_a(prim, SHADING_TYPES)
            inside = {m for m in self.meshes if Sdf.Path(m).HasPrefix(Sdf.Path(root))}
            present = {str(p.GetPath()): p for p in self._rendered_meshes(prim)} if prim \
                else {}
            for mesh in inside - set(present):
                self._forget(mesh)
            for mesh in present:
                mark(mesh, DirtyBits.DIRTY_TOPOLOGY)
        if rebuild_skel:
            self.skel = SkelBindings(self.stage)
            for mesh, prim in self._prims.items():
                if prim.HasAPI(UsdSkel.BindingAPI):
                    mark(mesh, DirtyBits.DIRTY_TOPOLOGY)
        if shading:
            for mesh in self.meshes:
                mark(mesh, DirtyBits.DIRTY_MATERIAL)
        for mesh, value in list(bits.items()):
            if not self._refresh(mesh, value):
                bits.pop(mesh)
        after = set(self.meshes)
        added = sorted(after - before)
        for mesh in added:
            bits[mesh] = DirtyBits.ALL
        moved = DirtyBits.DIRTY_TOPOLOGY | DirtyBits.DIRTY_TRANSFORM
        if added or before - after or any(value & moved for value in bits.values()):
            self.sampler.forget_bounds()  # the automatic framing sees the new shapes
        return bits, added, sorted(before - after)

    def _refresh(self, path: str, bits: int) -> bool:
        """Re-read what ``bits`` say changed; False when the mesh is no longer drawn."""
        if bits & DirtyBits.DIRTY_TOPOLOGY:
            return self._add_mesh(self.stage.GetPrimAtPath(path))
        record = self.meshes.get(path)
        if record is None:
            return False
        prim = self._prims[path]
        default = Usd.TimeCode.Default()
        if bits & DirtyBits.DIRTY_PRIMVAR:
            baked, wrinkled = self._wrinkle_source(prim, len(record.rest_points))
            record = dataclasses.replace(
                record, params=read_params(prim, record.rest_points, record.topology,
                                           self._relax_override),
                wrinkled=wrinkled, baked_range=baked.range_text() if baked is not None else None)
        if bits & DirtyBits.DIRTY_MATERIAL:
            record = dataclasses.replace(
                record, material=read_material(prim, record.topology, default))
        self.meshes[path] = record
        return True

    # -- static data -------------------------------------------------------------------
    def _mesh_record(self, prim: Usd.Prim, relax_iterations) -> MeshRecord | None:
        path = str(prim.GetPath())
        mesh = UsdGeom.Mesh(prim)
        default = Usd.TimeCode.Default()
        points_attr = mesh.GetPointsAttr()
        binding = self.skel.get(path)
        point_cached, rest_value, rest_attr_name = rest_pose(prim, skinned=binding is not None)
        has_rest = rest_attr_name == "primvars:rest"
        if rest_value is None or len(rest_value) == 0:
            _log.warning(f"mesh has no points; skipped ({path})")
            return None
        if len(rest_value) >= MAX_POINTS:  # before any per-point work
            raise UsdWrinkleError(f"mesh too large: {len(rest_value):,} points, usdwrinkle "
                                  f"handles fewer than {MAX_POINTS:,} per mesh", path,
                                  rest_attr_name)
        rest = finite_points(rest_value, path, rest_attr_name)
        first_points = static_value(points_attr)
        if has_rest and first_points is not None and len(rest) != len(first_points):
            raise UsdWrinkleError("primvars:rest and points differ in length", path,
                                  "primvars:rest")
        faces = read_faces(prim)
        topology = read_topology(prim, rest, faces)
        if topology is None:
            _log.warning(f"mesh has no faces; skipped ({path})")
            return None
        normals = plan_normals(prim, topology, faces[0], faces[1], faces[2], faces[3])
        skin = None
        if binding is not None:
            skel_query, skinning_query = binding
            if not skel_query:
                _log.warning(f"skel binding without a valid skeleton; treated as static "
                             f"({path})")
            else:
                with usd_diagnostics(forward=True):  # ComputeJointInfluences' complaints
                    skin = skin_data(path, skel_query, skinning_query, len(rest),
                                     self.skel.blend_queries.get(path))
        elif prim.HasAPI("SkelBindingAPI") and prim.GetRelationship("skel:skeleton"):
            targets = prim.GetRelationship("skel:skeleton").GetTargets()
            if targets:
                _log.warning(f"skel binding to a missing or unusable skeleton; treated as "
                             f"static ({path})")
        baked, wrinkled = self._wrinkle_source(prim, len(rest))
        params = read_params(prim, rest, topology, relax_iterations)
        material = read_material(prim, topology, default)
        return MeshRecord(path, topology, rest, vertex_normals(rest, topology), skin,
                          point_cached, wrinkled, params, material,
                          baked.range_text() if baked is not None else None, normals,
                          bool(static_value(mesh.GetDoubleSidedAttr())))

    # -- time ---------------------------------------------------------------------------
    def frame_range(self) -> list[float | None]:
        """The stage's authored start..end frames, or [default] when none (or when the
        stage's range is unusable: the commands refuse that unless --frames is given)."""
        try:
            return stage_frames(self.stage)
        except UsdWrinkleError:
            return [None]

    def first_frame(self) -> float | None:
        """frame_range()[0], without building the range."""
        try:
            span = stage_span(self.stage)
        except UsdWrinkleError:
            return None
        return None if span is None else float(span[0])

    def framing_range(self) -> list[float]:
        """The frames automatic framing takes its bounds over: the shot's range that a bake
        recorded in its layer (customLayerData usdwrinkle.shotStart, shotEnd), so that a
        bake of part of a shot is framed as the shot is; else frame_range."""
        data = self.stage.GetRootLayer().customLayerData.get("usdwrinkle", {})
        try:
            start, end = float(data["shotStart"]), float(data["shotEnd"])
        except (TypeError, ValueError, KeyError, AttributeError):
            return self.frame_range()
        if not (math.isfinite(start) and math.isfinite(end) and start <= end and
                end - start <= MAX_FRAMES):
            return self.frame_range()
        return [float(f) for f in np.arange(start, end + 0.5)]  # as stage_frames

    def prim(self, path: str) -> Usd.Prim:
        """The Usd.Prim of a mesh the scene keeps a record of."""
        return self._prims[path]

    # -- per frame (scene/sampling.py) -------------------------------------------------
    def sample_mesh(self, path: str, time: Usd.TimeCode, xform_cache,
                    with_baked: bool = True) -> MeshFrame:
        """One mesh at ``time`` (FrameSampler.sample_mesh)."""
        return self.sampler.sample_mesh(path, time, xform_cache, with_baked)

    def sample_meshes(self, frame: float, xform_cache=None, with_baked: bool = True) -> dict:
        """The MeshFrames of every mesh at ``frame`` (FrameSampler.sample_meshes)."""
        return self.sampler.sample_meshes(frame, xform_cache, with_baked)

    def sample(self, frame: float, aspect: float, camera_spec: str | None = None) -> FrameRecord:
        """Everything time-varying at ``frame`` (FrameSampler.sample)."""
        return self.sampler.sample(frame, aspect, camera_spec)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World bounds of the rendered meshes over the stage's range (FrameSampler.bounds)."""
        return self.sampler.bounds()

    def camera_aspect(self, camera_spec: str | None, frame: float) -> float | None:
        return self.sampler.camera_aspect(camera_spec, frame)

    def camera(self, camera_spec: str | None):
        """The camera prim ``--camera`` names (or the primary, or the first; None: no
        camera), kept until a resync; a missing one raises UsdWrinkleError."""
        return self.sampler.camera_prim(camera_spec)

    def corner_primvar(self, path: str, name: str) -> np.ndarray | None:
        """A primvar of a mesh as one value per triangle corner, (m, 3, c), at its
        default time (or first sample); None when the mesh has no usable such primvar."""
        from .material import corner_values

        primvar = UsdGeom.PrimvarsAPI(self._prims[path]).GetPrimvar(name)
        if not primvar or not primvar.HasValue():
            return None
        return corner_values(primvar, self.meshes[path].topology, Usd.TimeCode.EarliestTime())

    def check_baked(self, frames: list[float]) -> None:
        """Refuse, before any frame is drawn, a frame that a mesh's bake does not hold."""
        for source in self.baked.values():
            for frame in frames:
                source.check_covers(frame)


def refuse_overwriting_inputs(stage_path: str, outputs: list[str], stage=None) -> None:
    """Never write over the input stage or anything it reads: its layers (also those of
    unselected variants, and sublayers that do not exist yet), packages and textures,
    compared by real path and by inode."""
    if stage is not None:
        inputs = stage_inputs(stage)
    else:
        inputs = StageInputs()
        inputs.add_file(stage_path)
    for out in outputs:
        if inputs.protects(out):
            raise UsdWrinkleError(f"output '{out}' is an input of the stage: a layer, texture "
                                  "or other file it reads (choose another output path)")


__all__ = ["StageSceneDelegate", "open_stage", "refuse_overwriting_inputs"]
