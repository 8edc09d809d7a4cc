"""Per frame, what is time-varying on the stage: a MeshFrame per mesh (transforms,
skinning, point caches, baked fields, time-sampled colours and normal maps), the camera
and the lights, as a FrameRecord. The scene delegate (scene/stage.py) keeps the records
and processes the stage's edits; :class:`FrameSampler` reads its records and prims and
only samples."""
from __future__ import annotations

import functools
import weakref

import numpy as np
from pxr import Usd, UsdGeom

from ..process.errors import UsdWrinkleError
from ..process.limits import MAX_WORLD_COORDINATE
from ..usd.values import finite_in_float32, frame_of, static_value
from . import camera as camera_mod
from .lights import default_lights, light_prims, read_lights
from .material import corner_colors, read_normal_map
from .normals import sample_normals
from .records import FrameRecord, MeshFrame, MeshRecord
from .skel import check_blend_weights, dual_quaternions, sample_skin

RENDERED_PURPOSES = (UsdGeom.Tokens.default_, UsdGeom.Tokens.render)


def time_code(frame: float | None) -> Usd.TimeCode:
    """USD's time code of a frame (None: the default time)."""
    return Usd.TimeCode.Default() if frame is None else Usd.TimeCode(frame)


def check_transform(matrix: np.ndarray, path: str, frame, extent: float = 0.0) -> None:
    """Refuse a transform that is not finite, or that takes a mesh of half-size ``extent``
    beyond MAX_WORLD_COORDINATE (where float32 squares of lengths overflow on the GPU)."""
    matrix = np.ascontiguousarray(matrix, np.float64)
    # one 4x4 (a mesh's own transform, mostly the last frame's): its reach is remembered
    reach = _reach(matrix.tobytes(), float(extent)) if matrix.shape == (4, 4) else \
        _reach_of(matrix, float(extent))
    if reach is None:
        raise UsdWrinkleError("transform is not finite in float32 (NaN, Inf or beyond 3.4e38)",
                              path, "xformOp", frame)
    if reach > MAX_WORLD_COORDINATE:
        raise UsdWrinkleError(f"the mesh reaches {reach:.3g} scene units from the origin, "
                              f"beyond +-{MAX_WORLD_COORDINATE:g} (the GPU's float32 range); "
                              "check the units and the transforms", path, "xformOp", frame)


def _reach_of(matrix: np.ndarray, extent: float) -> float | None:
    """How far from the origin ``matrix`` (..., 4, 4) takes a mesh of half-size ``extent``,
    or None when it is not finite in float32."""
    if not finite_in_float32(matrix):
        return None
    scale = float(np.abs(matrix[..., :3, :3]).sum(axis=-2).max(initial=0.0))
    return scale * extent + float(np.abs(matrix[..., 3, :3]).max(initial=0.0))


@functools.lru_cache(maxsize=256)
def _reach(data: bytes, extent: float) -> float | None:
    return _reach_of(np.frombuffer(data, np.float64).reshape(4, 4), extent)


def finite_points(points, path, attribute, time=None):
    arr = np.asarray(points, dtype=np.float32).reshape(-1, 3)
    if not np.all(np.isfinite(arr)):
        frame = frame_of(time)
        raise UsdWrinkleError("points are not finite (NaN or Inf)", path, attribute, frame)
    return arr


def might_vary_in_time(prims: list[Usd.Prim]) -> bool:
    """Whether any of ``prims`` (lights, a camera) may read differently at another time:
    one of its attributes (a light's colour, intensity, shaping, a dome's texture; a
    camera's lens; its transform and visibility), or the transform or visibility of a
    prim above it, may vary in time."""
    for prim in prims:
        if any(attr.ValueMightBeTimeVarying() for attr in prim.GetAttributes()):
            return True
        parent = prim.GetParent()
        while parent and not parent.IsPseudoRoot():
            if parent.IsA(UsdGeom.Xformable) and \
                    UsdGeom.Xformable(parent).TransformMightBeTimeVarying():
                return True
            if parent.IsA(UsdGeom.Imageable) and \
                    UsdGeom.Imageable(parent).GetVisibilityAttr().ValueMightBeTimeVarying():
                return True
            parent = parent.GetParent()
    return False


class FrameSampler:
    """Samples the scene delegate ``scene``'s meshes, camera and lights at a frame. The
    meshes' bounds for the automatic framing are made on first use and kept until
    :meth:`forget_bounds` (an edit of the shapes). The camera prim and the light prims
    come from a walk of the stage, kept until a prim is resynced (added, removed,
    re-typed: ``scene.tracker.prim_resyncs``), as Hydra keeps its sprims."""

    def __init__(self, scene):
        # a proxy, not a reference: the delegate owns its sampler, and a cycle would keep
        # a dropped delegate (and the stage, with any unsaved edits of its layers that a
        # later Usd.Stage.Open of the same file would see) alive until a GC pass
        self.scene = weakref.proxy(scene)
        self._bounds = None
        self._walked = -1  # the tracker's prim_resyncs when the prims below were found
        self._cameras: dict = {}  # --camera spec -> its prim (or None: the framing)
        self._lights: list | None = None
        #: the lights and cameras read, while they do not vary in time (_kept), until the
        #: tracker's next notice
        self._kept_values: dict = {}
        self._varies: dict = {}
        self._kept_at = -1  # the tracker's notices when the two above were set

    def _walk_is_current(self) -> None:
        resyncs = self.scene.tracker.prim_resyncs
        if resyncs != self._walked:
            self._walked, self._cameras, self._lights = resyncs, {}, None

    def camera_prim(self, camera_spec: str | None):
        """find_camera's prim for ``camera_spec`` (a missing camera raises each time)."""
        self._walk_is_current()
        if camera_spec not in self._cameras:
            self._cameras[camera_spec] = camera_mod.find_camera(self.scene.stage, camera_spec)
        return self._cameras[camera_spec]

    def light_prims(self) -> list:
        self._walk_is_current()
        if self._lights is None:
            self._lights = light_prims(self.scene.stage)
        return self._lights

    def _kept(self, key, prims: list, read):
        """``read()``, kept under ``key`` while none of ``prims`` varies in time
        (might_vary_in_time) and the stage is not edited (the tracker's notices), else
        read again each time. Reading the lights and the camera each frame was a fifth of
        the paper's shirt frame on a GPU node."""
        notices = self.scene.tracker.notices
        if notices != self._kept_at:
            self._kept_at, self._kept_values, self._varies = notices, {}, {}
        group = key[0]
        if group not in self._varies:
            self._varies[group] = might_vary_in_time(prims)
        if self._varies[group]:
            return read()
        if key not in self._kept_values:
            self._kept_values[key] = read()
        return self._kept_values[key]

    def lights(self, time: Usd.TimeCode, xform_cache) -> list:
        """The stage's lights at ``time`` (read_lights), kept while they do not vary."""
        prims = self.light_prims()
        # a default value may differ from a single time sample: the default time apart
        return self._kept(("lights", time.IsDefault()), prims,
                          lambda: read_lights(self.scene.stage, time, xform_cache, prims))

    def camera(self, prim, time: Usd.TimeCode, aspect: float):
        """``prim``'s CameraRecord at ``time`` for ``aspect``, kept while it does not vary."""
        return self._kept((f"camera {prim.GetPath()}", time.IsDefault(), aspect), [prim],
                          lambda: camera_mod.usd_camera(prim, time, aspect))

    def forget_bounds(self) -> None:
        self._bounds = None

    def sample_mesh(self, path: str, time: Usd.TimeCode, xform_cache,
                    with_baked: bool = True) -> MeshFrame:
        """One mesh at ``time``; ``with_baked``: also its baked fields, if it has any."""
        record = self.scene.meshes[path]
        prim = self.scene.prim(path)
        frame = frame_of(time)
        baked = None
        if with_baked and path in self.scene.baked:
            baked = self.scene.baked[path].at(frame)
        local_to_world = np.asarray(xform_cache.GetLocalToWorldTransform(prim), np.float64)
        check_transform(local_to_world, path, frame, record.extent)
        visible = UsdGeom.Imageable(prim).ComputeVisibility(time) != UsdGeom.Tokens.invisible
        if record.skin is not None:
            skel_query, skinning_query = self.scene.skel.get(path)
            joints, skel_to_local, weights, active = sample_skin(
                path, skel_query, skinning_query, self.scene.skel.blend_queries.get(path), time,
                xform_cache, record.skin.num_subshapes)
            if joints.shape[0] < record.skin.num_joints:
                raise UsdWrinkleError(
                    f"{joints.shape[0]} skinning transforms for {record.skin.num_joints} joints",
                    path, "skel:joints", frame)
            if not np.all(np.isfinite(joints)):
                raise UsdWrinkleError("skinning transforms are not finite", path,
                                      "skel:skeleton", frame)
            check_blend_weights(path, record.skin, weights, frame, record.extent)
            check_transform(np.asarray(joints, np.float64).reshape(-1, 4, 4), path, frame,
                            record.extent)
            dqs = dual_quaternions(joints) if record.skin.method == "dualQuaternion" else None
            return MeshFrame(local_to_world, visible, None, joints, skel_to_local, weights,
                             active, baked, self._frame_normal_map(record, prim, time),
                             dual_quaternions=dqs,
                             corner_colors=self._frame_colors(record, prim, time))
        normals = sample_normals(prim, record.normals, time, frame) \
            if not time.IsDefault() else None
        points = None
        if record.point_cached:
            attr = UsdGeom.Mesh(prim).GetPointsAttr()
            value = static_value(attr) if time.IsDefault() else attr.Get(time)
            if value is None:
                raise UsdWrinkleError("points have no value", path, "points", frame)
            points = finite_points(value, path, "points", time)
            if len(points) != len(record.rest_points):
                raise UsdWrinkleError(
                    f"point count changes over time ({len(points)} != "
                    f"{len(record.rest_points)})", path, "points", frame)
            check_transform(local_to_world, path, frame, float(np.abs(points).max(initial=0)))
        return MeshFrame(local_to_world, visible, points, baked=baked,
                         normal_map=self._frame_normal_map(record, prim, time),
                         normals=normals, corner_colors=self._frame_colors(record, prim, time))

    @staticmethod
    def _frame_colors(record: MeshRecord, prim: Usd.Prim, time: Usd.TimeCode):
        """This frame's colours per corner, where the material's are time-sampled."""
        material = record.material
        if not material.color_varies or time.IsDefault():
            return None
        colors = corner_colors(prim, material.color_primvar, record.topology, time)
        if colors is None or colors[0].shape != material.corner_colors.shape:
            return None  # the default time's colours stay
        return colors[0]

    def _frame_normal_map(self, record: MeshRecord, prim: Usd.Prim, time: Usd.TimeCode):
        """The normal map of this frame, when its file is time-sampled (wrinkle maps)."""
        if not record.material.normal_map_varies:
            return None
        return read_normal_map(prim, record.topology, time)[0]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World bounds of the rendered meshes over the stage's range (at most 9 samples).

        Fixed for the whole shot, so automatic framing does not depend on which
        frames a farm chunk renders.
        """
        frames = self.scene.framing_range()
        if len(frames) > 9:
            frames = list(np.linspace(frames[0], frames[-1], 9))
        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        for f in frames:
            cache = UsdGeom.BBoxCache(time_code(f), list(RENDERED_PURPOSES),
                                      useExtentsHint=True)
            for path in self.scene.meshes:
                prim = self.scene.prim(path)
                box = cache.ComputeWorldBound(prim).ComputeAlignedRange()
                if box.IsEmpty():
                    continue
                lo = np.minimum(lo, np.asarray(box.GetMin()))
                hi = np.maximum(hi, np.asarray(box.GetMax()))
            meshes = self.scene.meshes
            skel_roots = {self.scene.skel.get(p)[0].GetSkeleton().GetPrim() for p in meshes
                          if meshes[p].skin is not None}
            for skel_prim in skel_roots:
                box = cache.ComputeWorldBound(skel_prim).ComputeAlignedRange()
                if not box.IsEmpty():
                    lo = np.minimum(lo, np.asarray(box.GetMin()))
                    hi = np.maximum(hi, np.asarray(box.GetMax()))
        return lo, hi

    def camera_aspect(self, camera_spec: str | None, frame: float) -> float | None:
        prim = self.camera_prim(camera_spec)
        return camera_mod.camera_aspect(prim, time_code(frame)) if prim else None

    def sample_meshes(self, frame: float, xform_cache=None, with_baked: bool = True) -> dict:
        """The MeshFrames of every mesh at ``frame`` (no camera or lights)."""
        time = time_code(frame)
        xform_cache = xform_cache or UsdGeom.XformCache(time)
        return {path: self.sample_mesh(path, time, xform_cache, with_baked)
                for path in self.scene.meshes}

    def sample(self, frame: float, aspect: float, camera_spec: str | None = None) -> FrameRecord:
        """Everything time-varying at ``frame`` (NaN: the default time)."""
        time = time_code(frame)
        xform_cache = UsdGeom.XformCache(time)
        meshes = self.sample_meshes(frame, xform_cache)
        prim = self.camera_prim(camera_spec)
        if prim is not None:
            cam = self.camera(prim, time, aspect)
        else:
            if self._bounds is None:
                self._bounds = self.bounds()
            cam = camera_mod.framing_camera(*self._bounds, self.scene.up_axis, aspect)
        lights = self.lights(time, xform_cache) or default_lights(cam.view)
        return FrameRecord(frame, cam, tuple(lights), meshes)


