"""The paint window's view: an orbit camera (tumble, track, dolly, as usdview and Maya
do), and rays through its pixels onto the posed meshes (picking). numpy only."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene.records import CameraRecord


@dataclass
class OrbitCamera:
    """Looks at ``centre`` from ``distance`` along the direction given by yaw and pitch
    (degrees) about the stage's up axis."""

    centre: np.ndarray
    distance: float
    yaw: float = 20.0
    pitch: float = 15.0
    fov: float = 30.0
    up_axis: str = "Y"

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(forward from the eye, right, up) in world space."""
        yaw, pitch = math.radians(self.yaw), math.radians(self.pitch)
        # in a Y-up frame: the eye sits at +Z for yaw 0, pitch 0
        back = np.array([math.sin(yaw) * math.cos(pitch), math.sin(pitch),
                         math.cos(yaw) * math.cos(pitch)])
        up = np.array([0.0, 1.0, 0.0])
        if self.up_axis == "Z":  # rotate Y-up to Z-up: (x, y, z) -> (x, -z, y)
            back = np.array([back[0], -back[2], back[1]])
            up = np.array([0.0, 0.0, 1.0])
        forward = -back
        right = np.cross(forward, up)
        right /= max(np.linalg.norm(right), 1e-12)
        true_up = np.cross(right, forward)
        return forward, right, true_up

    @property
    def eye(self) -> np.ndarray:
        return np.asarray(self.centre, np.float64) - self.basis()[0] * self.distance

    def record(self, aspect: float) -> CameraRecord:
        """The view and projection in the renderer's convention (row vectors: p @ view
        @ projection), as scene/camera.py builds them from a Gf.Frustum."""
        forward, right, up = self.basis()
        eye = self.eye
        view = np.eye(4)
        view[:3, 0], view[:3, 1], view[:3, 2] = right, up, -forward
        view[3, :3] = [-right @ eye, -up @ eye, forward @ eye]
        near = max(self.distance * 1e-3, 1e-4)
        far = self.distance * 100.0 + 1.0
        f = 1.0 / math.tan(math.radians(self.fov) / 2)
        projection = np.zeros((4, 4))
        projection[0, 0] = f / aspect
        projection[1, 1] = f
        projection[2, 2] = -(far + near) / (far - near)
        projection[2, 3] = -1.0
        projection[3, 2] = -2.0 * far * near / (far - near)
        return CameraRecord("<paint view>", view, projection, eye, aspect, (near, far))

    def tumble(self, dx: float, dy: float) -> None:
        """Orbit by a mouse move of (dx, dy) pixels."""
        self.yaw -= 0.4 * dx
        self.pitch = float(np.clip(self.pitch + 0.4 * dy, -89.0, 89.0))

    def track(self, dx: float, dy: float, height: int) -> None:
        """Pan by (dx, dy) pixels of a view ``height`` pixels high."""
        _, right, up = self.basis()
        scale = 2.0 * self.distance * math.tan(math.radians(self.fov) / 2) / max(height, 1)
        self.centre = np.asarray(self.centre, np.float64) - right * dx * scale + up * dy * scale

    def dolly(self, steps: float) -> None:
        """Zoom in (steps > 0) or out by wheel steps."""
        self.distance = float(np.clip(self.distance * 0.85 ** steps, 1e-4, 1e7))

    def frame(self, lo: np.ndarray, hi: np.ndarray, aspect: float) -> None:
        """Look at the box [lo, hi] so that it fills the view (F)."""
        lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
        self.centre = 0.5 * (lo + hi)
        radius = max(0.5 * float(np.linalg.norm(hi - lo)), 1e-3)
        fov = math.radians(self.fov)
        fov_min = min(fov, 2 * math.atan(math.tan(fov / 2) * aspect))
        self.distance = radius / math.sin(fov_min / 2) * 1.05

    def ray(self, x: float, y: float, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """The ray (origin, unit direction) through pixel (x, y), (0, 0) the top left."""
        camera = self.record(width / height)
        return pixel_ray(camera, x, y, width, height)


def pixel_ray(camera: CameraRecord, x: float, y: float, width: int,
              height: int) -> tuple[np.ndarray, np.ndarray]:
    """The world-space ray through pixel (x, y) of a ``camera`` image (row 0 at the top)."""
    ndc = np.array([2.0 * x / width - 1.0, 1.0 - 2.0 * y / height])
    inverse = np.linalg.inv(camera.view @ camera.projection)
    near = np.array([ndc[0], ndc[1], -1.0, 1.0]) @ inverse
    far = np.array([ndc[0], ndc[1], 1.0, 1.0]) @ inverse
    near, far = near[:3] / near[3], far[:3] / far[3]
    direction = far - near
    return near, direction / np.linalg.norm(direction)


def project(camera: CameraRecord, points: np.ndarray, width: int,
            height: int) -> tuple[np.ndarray, np.ndarray]:
    """World points to pixel coordinates ((n, 2), row 0 at the top) and whether each lies
    in front of the camera."""
    p = np.concatenate([np.asarray(points, np.float64), np.ones((len(points), 1))], axis=1)
    clip = p @ camera.view @ camera.projection
    w = clip[:, 3]
    safe = np.where(np.abs(w) > 1e-12, w, 1e-12)
    x = (clip[:, 0] / safe + 1.0) * 0.5 * width
    y = (1.0 - clip[:, 1] / safe) * 0.5 * height
    return np.stack([x, y], axis=1), w > 0


def ray_triangles(origin: np.ndarray, direction: np.ndarray, points: np.ndarray,
                  triangles: np.ndarray) -> tuple[int, float, np.ndarray] | None:
    """The nearest triangle a ray hits (Moller-Trumbore, both sides): (index, distance,
    barycentrics (b0, b1, b2)), or None."""
    if not len(triangles):
        return None
    p0, p1, p2 = (points[triangles[:, c]] for c in range(3))
    e1, e2 = p1 - p0, p2 - p0
    pvec = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, pvec)
    ok = np.abs(det) > 1e-18
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    tvec = origin - p0
    u = np.einsum("ij,ij->i", tvec, pvec) * inv
    qvec = np.cross(tvec, e1)
    v = (qvec @ direction) * inv
    t = np.einsum("ij,ij->i", e2, qvec) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    if not hit.any():
        return None
    t = np.where(hit, t, np.inf)
    best = int(np.argmin(t))
    return best, float(t[best]), np.array([1.0 - u[best] - v[best], u[best], v[best]])


def vertex_normals(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals, unit (zero where they cancel)."""
    p0, p1, p2 = (points[triangles[:, c]] for c in range(3))
    face = np.cross(p1 - p0, p2 - p0)
    normals = np.zeros_like(points, dtype=np.float64)
    for c in range(3):
        np.add.at(normals, triangles[:, c], face)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return np.where(length > 1e-30, normals / np.maximum(length, 1e-300), 0.0)
