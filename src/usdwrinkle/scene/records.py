"""Frozen numpy records: everything the renderer needs, with no Usd objects.

Spaces: "local" is the mesh prim's own space (where UsdSkel's baked points live);
"world" is the stage's world space. Matrices are 4x4 float64 in USD's row-vector
convention (p' = p @ M).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from .topology import Topology, closed_orientation


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
    subshape_normal_offsets : list of (p, 3) float32
        Per sub-shape, its normalOffsets ((0, 3) where none are authored): added to
        vertex-interpolated authored normals, as UsdSkel deforms normals.
    """

    method: str
    geom_bind: np.ndarray
    joint_indices: np.ndarray
    joint_weights: np.ndarray
    num_joints: int
    blend_point_indices: list = field(default_factory=list)
    subshape_offsets: list = field(default_factory=list)
    subshape_normal_offsets: list = field(default_factory=list)

    @property
    def num_subshapes(self) -> int:
        return len(self.subshape_offsets)

    @functools.cached_property
    def skinned(self) -> bool:
        """Joints move the points (else only blend shapes do, in the prim's own space)."""
        return self.num_joints > 0 and bool(np.any(self.joint_weights))

    @functools.cached_property
    def convex(self) -> bool:
        """Every point's joint weights are >= 0 and sum to 1: LBS keeps each posed point in
        the convex hull of its joints' images of it (render/bounds.py)."""
        weights = np.asarray(self.joint_weights, np.float64)
        return bool(np.all(weights >= 0) and np.all(np.abs(weights.sum(axis=1) - 1) <= 1e-4))


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
    slack : float, wrinkle:slack: the compression before the crests settle (the
        relaxation weighs the folds beyond it); the folds are drawn from
        contract.DRAWN_SLACK of it on (docs/method.md, "The fold law").
    hold : (n, 4) float32 or None, what held edges leave each point (wrinkle:held;
        params.held_weights): damping strength, and the unit rest vector from the holder;
        None: nothing held.
    width_note : str, where the width came from (check and the bake summary print it).
    crest_damping : float, the band in degrees within which the compression direction
        holds, followed beyond it (wrinkle:crestDamping; 0: none).
    coarsening : (n,) float32 or None, the most the mesh's compression coarsens each
        point's folds (folds.coarsening_cap of W and the rest curvature: COARSENING_MAX on
        flat cloth, 1 where the rest surface curves one way at about its tube's wavelength;
        None: COARSENING_MAX everywhere).
    slope : (SLOPE_SAMPLES,) float32 or None, the height profile's inextensible slope
        table (folds.slope_table; None: derived from height_profile where it is read).
    irregularity : float, the folds' spread of width (wrinkle:irregularity; 0: the
        paper's regular waves).
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
    slack: float = 0.0
    hold: np.ndarray | None = None
    width_note: str = ""
    crest_damping: float = 0.0
    coarsening: np.ndarray | None = None
    slope: np.ndarray | None = None
    irregularity: float = 0.0

    def slope_table(self) -> np.ndarray:
        """folds.slope_table of the height profile (``slope`` when given)."""
        if self.slope is not None:
            return np.asarray(self.slope, np.float32)
        from ..method.folds import slope_table

        return slope_table(self.height_profile)


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
        from ..images.colour import srgb_decode_8bit

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
class SurfaceParams:
    """UsdPreviewSurface's inputs other than diffuseColor and normal, constant, with the
    specification's fallbacks (a texture-driven input is read as its fallback)."""

    emissive_color: tuple = (0.0, 0.0, 0.0)
    use_specular_workflow: bool = False
    specular_color: tuple = (0.0, 0.0, 0.0)
    metallic: float = 0.0
    roughness: float = 0.5
    clearcoat: float = 0.0
    clearcoat_roughness: float = 0.01
    opacity: float = 1.0
    opacity_threshold: float = 0.0
    ior: float = 1.5
    occlusion: float = 1.0


@dataclass(frozen=True)
class MaterialRecord:
    """UsdPreviewSurface diffuse colour, constant or from a texture, and a normal map.

    surface : the other UsdPreviewSurface inputs, or None: no UsdPreviewSurface is bound,
        and the mesh is drawn as Storm draws it then (its fallback surface: displayColor
        and displayOpacity, lit by Lambert and a faint Blinn lobe).
    opacity : displayOpacity, for the fallback surface.

    texture : TextureImage (row 0 at t = 0, the bottom), or None.
    corner_st : (m, 3, 2) float32 texture coordinates per triangle corner, or None.
    normal_map : the normal map at the default time (or the first frame's), or None.
    normal_map_varies : its file is time-sampled (per-frame wrinkle maps): each frame
        reads its own (MeshFrame.normal_map).
    wrinkle_maps : the material is one that ``bake --maps`` wrote (its normal map holds
        the wrinkles already).
    corner_colors : (m, 3, 3) float32 linear colours per triangle corner that multiply
        the diffuse colour, or None: a displayColor that is not constant (Storm's fallback
        surface), or the primvar a UsdPrimvarReader_float3 feeds diffuseColor from.
    color_primvar : that primvar's name; color_varies: it is time-sampled (each frame
        reads its own, MeshFrame.corner_colors).
    """

    diffuse_color: np.ndarray
    texture: TextureImage | None = None
    corner_st: np.ndarray | None = None
    texture_scale: np.ndarray = field(default_factory=lambda: np.ones(4, np.float32))
    texture_bias: np.ndarray = field(default_factory=lambda: np.zeros(4, np.float32))
    normal_map: NormalMapRecord | None = None
    normal_map_varies: bool = False
    wrinkle_maps: bool = False
    surface: SurfaceParams | None = None
    corner_colors: np.ndarray | None = None
    color_primvar: str | None = None
    color_varies: bool = False
    opacity: float = 1.0

    @property
    def translucent(self) -> bool:
        """A surface that lets what is behind it show: opacity (or displayOpacity) below 1,
        and no opacityThreshold (a threshold cuts out instead: masked, opaque)."""
        if self.surface is None:
            return self.opacity < 1.0
        return self.surface.opacity < 1.0 and self.surface.opacity_threshold <= 0.0


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
    #: how the shading normals are made (scene/normals.py); None: smooth
    normals: object | None = None
    #: back faces are shaded with the flipped normal (else as Storm: unlit)
    double_sided: bool = False

    @functools.cached_property
    def extent(self) -> float:
        """The largest |coordinate| of the rest points (scene/stage.py: check_transform)."""
        return float(np.abs(self.rest_points).max(initial=0.0))

    @functools.cached_property
    def joint_boxes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per joint that moves some point (a weight > 0): its index, and the lower and
        upper corners of the box of the rest points it moves ((k,), (k, 3), (k, 3);
        render/bounds.py)."""
        skin = self.skin
        points = np.asarray(self.rest_points, np.float64)
        if skin is None or not len(points):
            return np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 3))
        indices = np.asarray(skin.joint_indices, np.int64)
        moved = (np.asarray(skin.joint_weights) > 0) & (indices >= 0) & \
            (indices < skin.num_joints)
        rows, columns = np.nonzero(moved)
        joint_of = indices[rows, columns]
        joints = np.unique(joint_of)
        slot = np.searchsorted(joints, joint_of)
        lo = np.full((len(joints), 3), np.inf)
        hi = np.full((len(joints), 3), -np.inf)
        np.minimum.at(lo, slot, points[rows])
        np.maximum.at(hi, slot, points[rows])
        return joints, lo, hi

    @functools.cached_property
    def closed(self) -> int:
        """topology.closed_orientation of the rest pose: +1 a closed surface wound outward,
        -1 inward, 0 open (render/bounds.py)."""
        return closed_orientation(self.rest_points, self.topology.triangles)


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
    normals: np.ndarray | None = None           # (K, 3) authored normals, when time-sampled
    #: (m, 3, 3) this frame's corner colours, when the material's are time-sampled
    corner_colors: np.ndarray | None = None
    #: DQS: the joints' transforms split as UsdSkel does (scene/skel.dual_quaternions:
    #: real (J, 4) xyzw, dual (J, 4) xyzw, scale (J, 3, 3), any joint scales), made by the
    #: scene so that the GPU side needs no Gf
    dual_quaternions: tuple | None = None


@dataclass(frozen=True)
class CameraRecord:
    """A perspective or orthographic view. view: world -> eye; projection: eye -> clip."""

    path: str
    view: np.ndarray
    projection: np.ndarray
    position: np.ndarray
    aspect: float
    #: clippingRange (near, far) in scene units along the view direction
    clipping: tuple = (1.0, 1.0e6)


@dataclass(frozen=True)
class LightRecord:
    """A light as Storm lights a surface (scene/lights.py, docs/method.md "Lights").

    kind : "directional", "positional" or "dome".
    color : (3,) the colour c: inputs:color x blackbody(colorTemperature) x intensity x
        2^exposure x the light's area (solid angle for a distant light) unless
        inputs:normalize; times inputs:diffuse (``specular`` times inputs:specular).
    vector : (3,) world space; directional: the unit vector towards the light;
        positional: its position.
    attenuate : 1/d^2 falloff (every positional light but usdview's camera light).
    spot_direction, spot_cutoff, spot_falloff : rect and disk lights emit into the
        cone of inputs:shaping:cone:angle (degrees; 180: everywhere) about their -Z,
        weighted cos^falloff (inputs:shaping:focus).
    ambient : (3,) the ambient colour (usdview's camera light: 0.01), used by the
        fallback surface only.
    dome_sh : (9, 3) dome lights: the SH9 coefficients of the environment's radiance
        (times c) in world directions, or None: its diffuse irradiance.
    """

    kind: str
    color: np.ndarray
    specular: np.ndarray
    vector: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    attenuate: bool = False
    spot_direction: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -1.0]))
    spot_cutoff: float = 180.0
    spot_falloff: float = 0.0
    ambient: np.ndarray = field(default_factory=lambda: np.zeros(3))
    dome_sh: np.ndarray | None = None
    #: a textured dome's environment (TextureImage, lat-long, rows bottom-up) and the
    #: rotation from world to dome directions (row-vector 3x3): its specular reflections
    dome_texture: object | None = None
    world_to_dome: np.ndarray | None = None
    dome_key: str | None = None


@dataclass(frozen=True)
class FrameRecord:
    time: float
    camera: CameraRecord
    lights: tuple
    meshes: dict
