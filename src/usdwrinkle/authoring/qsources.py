"""Paint q and width from textures, directions and DCC primvars.

Flow maps follow the common convention: the R and G channels hold the tangent
direction in texture space as ``2 c - 1`` along u and v, with v up (t = 0 at the
bottom row of the image, as USD's st). The amount comes from its own channel, or
from the length of the decoded vector. Texture-space directions become rest-space
tangents through the mesh's dP/d(s,t).
"""
from __future__ import annotations

import numpy as np
from pxr import Usd, UsdGeom

from ..process.errors import UsdWrinkleError
from ..scene.material import corner_values
from ..scene.stage import read_topology, rest_pose
from ..scene.topology import Topology, vertex_normals
from ..usd.values import static_flattened

CHANNELS = {"R": 0, "G": 1, "B": 2, "A": 3}


class MeshSurface:
    """The rest pose of one mesh, with what painting needs: normals, UVs, dP/dUV."""

    def __init__(self, prim: Usd.Prim):
        self.prim = prim
        self.path = str(prim.GetPath())
        skinned = prim.HasAPI("SkelBindingAPI") and bool(
            prim.GetRelationship("skel:skeleton").GetTargets())
        _, value, _ = rest_pose(prim, skinned=skinned)
        if value is None or len(value) == 0:
            raise UsdWrinkleError("mesh has no points", self.path, "points")
        self.rest = np.asarray(value, np.float64).reshape(-1, 3)
        topology = read_topology(prim, self.rest.astype(np.float32))
        if topology is None:
            raise UsdWrinkleError("mesh has no faces", self.path, "faceVertexCounts")
        self.topology: Topology = topology
        self.normals = vertex_normals(self.rest, topology).astype(np.float64)

    def project(self, vectors: np.ndarray) -> np.ndarray:
        """Project (n, 3) vectors onto each vertex's rest tangent plane."""
        return vectors - np.sum(vectors * self.normals, axis=1, keepdims=True) * self.normals

    def corner_uv(self, name: str) -> np.ndarray:
        primvar = UsdGeom.PrimvarsAPI(self.prim).GetPrimvar(name)
        if not primvar or not primvar.HasValue():
            raise UsdWrinkleError(f"texture coordinates '{name}' not found (use `uv`)",
                                  self.path, f"primvars:{name}")
        corners = corner_values(primvar, self.topology, Usd.TimeCode.Default())
        if corners is None or corners.shape[-1] < 2:
            raise UsdWrinkleError(f"texture coordinates '{name}' are not usable "
                                  "(need float2 values, vertex or faceVarying)",
                                  self.path, f"primvars:{name}")
        return corners[..., :2].astype(np.float64)

    def vertex_uv(self, corner_uv: np.ndarray) -> np.ndarray:
        """Per-vertex UVs: faceVarying corners are averaged per vertex."""
        return _average_corners(self, corner_uv)

    def uv_frames(self, corner_uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """dP/du and dP/dv per vertex: each triangle's, area weighted, averaged."""
        tri = self.topology.triangles
        p0, p1, p2 = (self.rest[tri[:, c]] for c in range(3))
        e1, e2 = p1 - p0, p2 - p0
        d1 = corner_uv[:, 1] - corner_uv[:, 0]
        d2 = corner_uv[:, 2] - corner_uv[:, 0]
        det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
        ok = np.abs(det) > 1e-20
        safe = np.where(ok, det, 1.0)[:, None]
        dp_du = np.where(ok[:, None], (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) / safe, 0.0)
        dp_dv = np.where(ok[:, None], (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) / safe, 0.0)
        area = 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1)[:, None]
        n = len(self.rest)
        du, dv = np.zeros((n, 3)), np.zeros((n, 3))
        for c in range(3):
            np.add.at(du, tri[:, c], dp_du * area)
            np.add.at(dv, tri[:, c], dp_dv * area)
        return du, dv


def read_image(path: str) -> np.ndarray:
    """(h, w, 4) float32 in [0, 1] as stored (no colour conversion: data, not colour)."""
    from ..images.imagefiles import read_float_image
    from ..process.limits import MAX_TEXTURE_SIZE

    try:
        pixels, _ = read_float_image(path, MAX_TEXTURE_SIZE)
    except OSError as exc:
        raise UsdWrinkleError(str(exc)) from None
    out = np.zeros((*pixels.shape[:2], 4), np.float32)
    out[..., 3] = 1.0
    channels = min(pixels.shape[2], 4)
    if channels == 1:
        out[..., :3] = pixels[..., :1]
    else:
        out[..., :channels] = pixels[..., :channels]
    return out


def sample(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear lookup with repeat wrap; v up (t = 0 is the bottom row). (n, 4)."""
    height, width = image.shape[:2]
    x = np.asarray(uv[:, 0], np.float64) * width - 0.5
    y = (1.0 - np.asarray(uv[:, 1], np.float64)) * height - 0.5
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    x0, x1 = x0 % width, (x0 + 1) % width
    y0, y1 = y0 % height, (y0 + 1) % height
    top = image[y0, x0] * (1 - fx) + image[y0, x1] * fx
    bottom = image[y1, x0] * (1 - fx) + image[y1, x1] * fx
    return top * (1 - fy) + bottom * fy


def q_uniform(surface: MeshSurface, direction, amount: float) -> np.ndarray:
    """A rest-space direction projected onto each tangent plane, with |q| = amount."""
    d = np.asarray(direction, np.float64).reshape(1, 3)
    if not np.all(np.isfinite(d)) or not np.any(d):
        raise UsdWrinkleError("`q` needs a finite, non-zero direction")
    d = d / np.abs(d).max()  # only the direction counts: 1e308 must not overflow
    tangent = surface.project(np.repeat(d, len(surface.rest), axis=0))
    length = np.linalg.norm(tangent, axis=1, keepdims=True)
    # where the direction is the normal itself there is no tangent direction: no q
    return np.where(length > 1e-9, tangent / np.maximum(length, 1e-30) * amount, 0.0)


def q_from_flow_map(surface: MeshSurface, image_path: str, uv_name: str = "st",
                    amount_channel: str | None = None) -> np.ndarray:
    """q from a flow map (see the module's docstring for the convention)."""
    image = read_image(image_path)
    corner_uv = surface.corner_uv(uv_name)
    texel = sample(image, surface.vertex_uv(corner_uv))
    flow = 2.0 * texel[:, :2] - 1.0  # texture-space direction, v up
    du, dv = surface.uv_frames(corner_uv)
    tangent = surface.project(flow[:, :1] * du + flow[:, 1:2] * dv)
    length = np.linalg.norm(tangent, axis=1, keepdims=True)
    direction = np.where(length > 1e-12, tangent / np.maximum(length, 1e-30), 0.0)
    if amount_channel:
        amount = np.clip(texel[:, CHANNELS[amount_channel.upper()]], 0.0, 1.0)
    else:
        amount = np.clip(np.linalg.norm(flow, axis=1), 0.0, 1.0)
    return direction * amount[:, None]


def width_from_texture(surface: MeshSurface, image_path: str, base_width: float,
                       uv_name: str = "st") -> np.ndarray:
    """Per-vertex width: the base width scaled by a grey map (its luminance)."""
    image = read_image(image_path)
    texel = sample(image, surface.vertex_uv(surface.corner_uv(uv_name)))
    grey = texel[:, :3] @ np.array([0.2126, 0.7152, 0.0722])
    return base_width * grey


def q_from_primvar(surface: MeshSurface, name: str) -> np.ndarray:
    """q from a DCC's painted vertex primvar: a vector as is, a colour decoded as 2c - 1."""
    primvar = UsdGeom.PrimvarsAPI(surface.prim).GetPrimvar(name)
    if not primvar or not primvar.HasValue():
        raise UsdWrinkleError(f"primvar '{name}' not found", surface.path, f"primvars:{name}")
    values = static_flattened(primvar)
    arr = np.asarray(values, np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise UsdWrinkleError(f"primvar '{name}' must hold 3-vectors or colours",
                              surface.path, f"primvars:{name}")
    interpolation = primvar.GetInterpolation()
    if interpolation == UsdGeom.Tokens.faceVarying:
        corners = corner_values(primvar, surface.topology, Usd.TimeCode.Default())
        arr = _average_corners(surface, corners)
    elif len(arr) != len(surface.rest):
        raise UsdWrinkleError(f"primvar '{name}' has {len(arr)} values for "
                              f"{len(surface.rest)} points (need vertex or faceVarying)",
                              surface.path, f"primvars:{name}")
    if primvar.GetTypeName().role == "Color":
        arr = 2.0 * arr - 1.0
    q = surface.project(arr)
    length = np.linalg.norm(q, axis=1, keepdims=True)
    return np.where(length > 1.0, q / np.maximum(length, 1e-30), q)


def _average_corners(surface: MeshSurface, corners: np.ndarray) -> np.ndarray:
    n = len(surface.rest)
    sums = np.zeros((n, corners.shape[-1]))
    counts = np.zeros(n)
    np.add.at(sums, surface.topology.triangles.ravel(), corners.reshape(-1, corners.shape[-1]))
    np.add.at(counts, surface.topology.triangles.ravel(), 1)
    return sums / np.maximum(counts, 1)[:, None]
