"""Where each mesh can be on screen this frame, from its pose alone (no GPU readback):
which side of it the draw pass may leave out, and the rectangle of the frame that the
draw clears and the resolve reads.

A mesh's bound is a set of points in eye space whose convex hull contains its posed
surface:

- a rigid mesh or a point cache: the eight corners of its points' box;
- an LBS-skinned mesh whose weights are convex per point (>= 0, summing to 1): per
  joint, the eight corners of the box of the rest points that joint moves (grown by
  the largest reach of this frame's blend shapes), carried by that joint's transform. A
  posed point is a convex blend of its joints' images of the rest point, each inside
  that joint's carried box, so it lies in the hull.

A mesh that has no such bound (DQS, weights that are not convex) makes the whole frame
its rectangle and is never culled. Every test is conservative: where it cannot prove a
shortcut harmless, the frame is drawn as Storm draws it.

Culling. Storm draws both sides of every mesh (usdview culls nothing by default); a
single-sided mesh's back faces are shaded unlit. Leaving them out halves the draw on a
software rasteriser (CesiumMan at 960x540 on llvmpipe: 44 -> 22 ms), but only where no
back face can be seen:

- the mesh is single-sided and opaque (a translucent or cut-out surface shows its inside);
- its rest pose is a closed surface, consistently wound (scene/topology.py:
  closed_orientation); the side facing away is the back (or, for a surface wound inward,
  the front, which the camera never sees either);
- this frame its bound lies between the near and far planes (a clipping plane opens it),
  which also puts a perspective camera outside it;
- its pose keeps the winding: no joint's transform mirrors, a point cache's signed volume
  keeps the rest pose's sign, and the mesh's own transform's handedness flips the side.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene.records import CameraRecord, MeshFrame, MeshRecord

#: pixels added around a mesh's projected bound (rasterisation rounds to pixel centres and
#: multisample positions; the centroid-sampled edges stay inside the triangle anyway)
RECT_MARGIN = 2
#: relative rounding of float32 posed points (a few ulps of 2^-24, generously)
FLOAT32_PAD = 1e-6


@dataclass(frozen=True)
class EyeBound:
    """Points in eye space, (k, 3), whose convex hull holds a mesh's posed surface;
    ``mirrored``: some transform of the pose mirrors the mesh (its winding is unknown)."""

    points: np.ndarray
    mirrored: bool = False

    def depth_range(self) -> tuple[float, float]:
        """(nearest, farthest) distance along the view direction (eye space -Z), widened
        by what float32 skinning may round (the posed points are float32 on the GPU)."""
        depth = -self.points[:, 2]
        pad = FLOAT32_PAD * float(np.abs(self.points).max(initial=0.0))
        return float(depth.min()) - pad, float(depth.max()) + pad


_CORNERS = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float)


def _box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(..., 8, 4) homogeneous corners of boxes (..., 3)."""
    corners = lo[..., None, :] + (hi - lo)[..., None, :] * _CORNERS
    return np.concatenate([corners, np.ones(corners.shape[:-1] + (1,))], axis=-1)


def eye_bound(record: MeshRecord, frame: MeshFrame, view: np.ndarray) -> EyeBound | None:
    """The bound of one mesh this frame in the eye space of ``view`` (world -> eye), or
    None when its pose has none (see the module's note)."""
    local_to_eye = frame.local_to_world @ view
    skin = record.skin
    if skin is None or frame.joint_transforms is None:
        points = frame.points if frame.points is not None else record.rest_points
        points = np.asarray(points, np.float64).reshape(-1, 3)
        if not len(points):
            return None
        eye = _box_corners(points.min(axis=0), points.max(axis=0)) @ local_to_eye
        return EyeBound(eye[:, :3])
    reach = 0.0  # how far this frame's blend shapes move a point, at most
    if frame.subshape_weights is not None and skin.subshape_offsets:
        reach = sum(abs(float(w)) * float(np.abs(o).max(initial=0.0))
                    for w, o in zip(frame.subshape_weights, skin.subshape_offsets,
                                    strict=False))
    if not skin.skinned:  # blend shapes alone, in the prim's space (the skin pass's rule)
        points = np.asarray(record.rest_points, np.float64)
        if not len(points):
            return None
        eye = _box_corners(points.min(axis=0) - reach, points.max(axis=0) + reach) @ \
            local_to_eye
        return EyeBound(eye[:, :3])
    if skin.method != "classicLinear" or not skin.convex:
        return None
    joints, lo, hi = record.joint_boxes
    if not len(joints):
        return None
    to_eye = skin.geom_bind[None] @ frame.joint_transforms[joints] @ \
        frame.skel_to_local[None] @ local_to_eye[None]
    eye = _box_corners(lo - reach, hi + reach) @ to_eye  # (k, 8, 4)
    mirrored = bool(np.any(np.linalg.det(to_eye[:, :3, :3]) <= 0))
    return EyeBound(eye[..., :3].reshape(-1, 3), mirrored)


def culled_side(record: MeshRecord, frame: MeshFrame, camera: CameraRecord,
                bound: EyeBound | None) -> str | None:
    """"back" or "front" (the winding as the draw pass sees it), or None: draw both."""
    if bound is None or bound.mirrored or record.double_sided or record.closed == 0 or \
            record.material.translucent:
        return None
    surface = record.material.surface
    if surface is not None and surface.opacity_threshold > 0.0:
        return None
    if frame.points is not None and record.skin is None:
        p = np.asarray(frame.points, np.float64)[record.topology.triangles]
        volume = float(np.einsum("ij,ij->", p[:, 0], np.cross(p[:, 1], p[:, 2])))
        if not np.isfinite(volume) or volume * record.closed <= 0:
            return None  # the cache turned the surface inside out (or flat)
    near, far = bound.depth_range()
    clip_near, clip_far = camera.clipping
    margin = 1e-4 * max(abs(clip_near), abs(clip_far - clip_near))
    if not (near > clip_near + margin and far < clip_far - margin):
        return None
    side = record.closed
    if np.linalg.det(frame.local_to_world[:3, :3]) < 0:
        side = -side
    return "back" if side > 0 else "front"


def screen_rect(bounds, eye_to_clip: np.ndarray, width: int,
                height: int) -> tuple[int, int, int, int] | None:
    """The rectangle (x0, y0, x1, y1), in the framebuffer's pixels (x1, y1 exclusive),
    that holds every bound of ``bounds`` projected by ``eye_to_clip`` (row-vector), or
    None (the whole frame) when one of them is None or reaches behind the camera."""
    bounds = list(bounds)
    if any(bound is None for bound in bounds):
        return None
    if not bounds:
        return (0, 0, 0, 0)
    points = np.concatenate([bound.points for bound in bounds])
    clip = np.c_[points, np.ones(len(points))] @ eye_to_clip
    w = clip[:, 3]
    if not np.all(np.isfinite(clip)) or np.any(w <= 1e-9 * np.abs(clip[:, :3]).max()):
        return None
    ndc = clip[:, :2] / w[:, None]
    px = (ndc[:, 0] + 1.0) * 0.5 * width
    py = (ndc[:, 1] + 1.0) * 0.5 * height
    x0 = max(int(np.floor(px.min())) - RECT_MARGIN, 0)
    x1 = min(int(np.ceil(px.max())) + RECT_MARGIN, width)
    y0 = max(int(np.floor(py.min())) - RECT_MARGIN, 0)
    y1 = min(int(np.ceil(py.max())) + RECT_MARGIN, height)
    if x1 <= x0 or y1 <= y0:
        return (0, 0, 0, 0)
    return (x0, y0, x1, y1)
