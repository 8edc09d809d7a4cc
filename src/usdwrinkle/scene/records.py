"""Frozen numpy records: everything the renderer needs, with no Usd objects.

Spaces: "local" is the mesh prim's own space (where UsdSkel's baked points live);
"world" is the stage's world space. Matrices are 4x4 float64 in USD's row-vector
convention (p' = p @ M).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from .topology import Topology


@dataclass(frozen=True)
class SkinData:
    """UsdSkel skinning of one mesh, in the mesh's joint order.

    Attributes
    ----------
    method : str
        ``classicLinear`` or ``dualQuaternion``.
    geom_bind : (4, 4) float64
        geomBindTransform (mesh local -> skeleton bind space).
    joint_indices : (n, k) int32
    joint_weights : (n, k) float32
    num_joints : int
    blend_point_indices : list of (p,) int32 or None
        Per blend shape, the points it moves (None: all points).
    subshape_offsets : list of (p, 3) float32
        Per sub-shape (UsdSkelBlendShapeQuery order), its point offsets.
    """

    method: str
    geom_bind: np.ndarray
    joint_indices: np.ndarray
    joint_weights: np.ndarray
    num_joints: int
    blend_point_indices: list = field(default_factory=list)
    subshape_offsets: list = field(default_factory=list)

    @property
    def num_subshapes(self) -> int:
        return len(self.subshape_offsets)


@dataclass(frozen=True)
class WrinkleParams:
    """Per-mesh wrinkle controls, resolved with fallbacks.

    q : (n, 3) float32, rest-space wrinkle vectors (zero where none painted).
    width : (n,) float32, rest wavelength W per point.
    amplitude_scale : float, s.
    height_profile, gradient_profile : (p,) float32 over one period [0, 2pi).
    relax_iterations : int.
    biaxial : float, the second wave system's weight in [0, 1] (0: one system).
    tension : float, the tension wave's amplitude factor (0: no tension wrinkles).
    tension_threshold : float, the strain below which no tension wrinkle appears.
    """

    q: np.ndarray
    width: np.ndarray
    amplitude_scale: float
    height_profile: np.ndarray
    gradient_profile: np.ndarray
    relax_iterations: int
    biaxial: float = 0.0
    tension: float = 0.0
    tension_threshold: float = 0.02


@dataclass(frozen=True)
class TextureImage:
    """Decoded texture pixels, (h, w, 4), row 0 at t = 0 (the bottom of the image).

    pixels : uint8 codes of an 8-bit file (uploaded as they are: the GPU decodes sRGB
        when ``srgb``, before filtering), or float32 values (linear, or raw data).
    srgb : the uint8 codes are sRGB encoded.
    """

    pixels: np.ndarray
    srgb: bool = False

    @property
    def shape(self) -> tuple:
        return self.pixels.shape

    def linear(self) -> np.ndarray:
        """(h, w, 4) float32: what the shaders sample."""
        from ..colour import srgb_decode_8bit

        if self.pixels.dtype != np.uint8:
            return self.pixels
        values = self.pixels.astype(np.float32) / 255.0
        if self.srgb:
            values[..., :3] = srgb_decode_8bit(values[..., :3])
        return values


@dataclass(frozen=True)
class NormalMapRecord:
    """UsdPreviewSurface ``inputs:normal`` from a UsdUVTexture: a tangent-space normal map.

    tiles : tuple of (tile, TextureImage)
        One texture (tile -1: it repeats), or the tiles of a UDIM set (tile
        u + 10 v for file 1001 + u + 10 v), all of one size.
    corner_st : (m, 3, 2) float32 texture coordinates per triangle corner.
    scale, bias : the texture's inputs:scale and inputs:bias (the decoded normal is
        texel * scale + bias).
    key : what was read (the resolved file names): a frame that names the same files
        re-uses the uploaded textures.
    """

    tiles: tuple
    corner_st: np.ndarray
    scale: np.ndarray
    bias: np.ndarray
    key: str


@dataclass(frozen=True)
class MaterialRecord:
    """UsdPreviewSurface diffuse colour, constant or from a texture, and a normal map.

    texture : TextureImage (row 0 at t = 0, the bottom), or None.
    corner_st : (m, 3, 2) float32 texture coordinates per triangle corner, or None.
    normal_map : the normal map at the default time (or the first frame's), or None.
    normal_map_varies : its file is time-sampled (per-frame wrinkle maps): each frame
        reads its own (MeshFrame.normal_map).
    wrinkle_maps : the material is one that ``bake --maps`` wrote (its normal map holds
        the wrinkles already).
    """

    diffuse_color: np.ndarray
    texture: TextureImage | None = None
    corner_st: np.ndarray | None = None
    texture_scale: np.ndarray = field(default_factory=lambda: np.ones(4, np.float32))
    texture_bias: np.ndarray = field(default_factory=lambda: np.zeros(4, np.float32))
    normal_map: NormalMapRecord | None = None
    normal_map_varies: bool = False
    wrinkle_maps: bool = False


@dataclass(frozen=True)
class MeshRecord:
    """What does not change over time: topology, rest pose, skinning, parameters."""

    path: str
    topology: Topology
    rest_points: np.ndarray            # (n, 3) float32, local
    rest_normals: np.ndarray           # (n, 3) float32, local
    skin: SkinData | None
    point_cached: bool
    wrinkled: bool
    params: WrinkleParams
    material: MaterialRecord
    #: the frames of the mesh's baked wave fields ("1..24", "default time"), or None:
    #: a render draws them instead of running crush and relax (scene/baked.py)
    baked_range: str | None = None

    @functools.cached_property
    def extent(self) -> float:
        """The largest |coordinate| of the rest points (scene/stage.py: check_transform)."""
        return float(np.abs(self.rest_points).max(initial=0.0))


@dataclass(frozen=True)
class MeshFrame:
    """The time-varying part of one mesh at one frame."""

    local_to_world: np.ndarray                  # (4, 4) float64
    visible: bool = True
    points: np.ndarray | None = None            # (n, 3) float32 local (point cache, static)
    joint_transforms: np.ndarray | None = None  # (J, 4, 4) float64, skeleton space, mesh order
    skel_to_local: np.ndarray | None = None     # (4, 4) float64
    subshape_weights: np.ndarray | None = None  # (S,) float32 dense over sub-shapes
    active_subshapes: tuple = ()                # ((blend_shape, sub_shape), ...)
    baked: object | None = None                 # scene.baked.BakedFields at this frame
    normal_map: NormalMapRecord | None = None   # this frame's, when its file is time-sampled


@dataclass(frozen=True)
class CameraRecord:
    """A perspective or orthographic view. view: world -> eye; projection: eye -> clip."""

    path: str
    view: np.ndarray
    projection: np.ndarray
    position: np.ndarray
    aspect: float


@dataclass(frozen=True)
class LightRecord:
    """kind: distant | sphere | dome. radiance = colour * intensity * 2^exposure."""

    kind: str
    radiance: np.ndarray
    direction: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -1.0]))
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    radius: float = 0.5


@dataclass(frozen=True)
class FrameRecord:
    time: float
    camera: CameraRecord
    lights: tuple
    meshes: dict
