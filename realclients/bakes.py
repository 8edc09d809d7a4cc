"""usdwrinkle's bake outputs as real clients show them, against usdwrinkle's own render.

The *wrinkle contribution* of a renderer is its wrinkled image minus its image of the same
shot without wrinkles, so that what each renderer does its own way (lights, filtering)
drops out and the wrinkles remain (issue 23):
- usdwrinkle: ``render`` minus ``render --no-wrinkles`` of the stage;
- Storm, maps: the ``--maps normal`` layer minus the ``--with-points`` layer (the same
  posed points and normals without the maps, so that Storm's skinned-normals limitation
  drops out too);
- Storm, geometry: the ``--geometry`` layer with the render purpose, likewise.

The stage's textures are flattened to one grey first (shots.flat_textures): the maps carry
the wrinkles' shading, not usdwrinkle's bending of the texture coordinates, which moves
the texture's pattern (docs/method.md, "Maps").

Decoded normals: each renderer's shading normal per pixel by photometric stereo, six
renders with one distant light each along +-X, +-Y, +-Z (n ~ I(+a) - I(-a) per axis for a
Lambertian surface); the same procedure on both renderers, so that the shading model's own
factors are common to both and cancel in the angle between them.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from . import cycles, storm
from .compare import eroded as erode
from .compare import read_rgba8
from .shots import (
    CORPUS,
    SAMPLES,
    _usdwrinkle,
    flat_textures,
    has_lights,
    over_layer,
    shared_camera,
)


@dataclass(frozen=True)
class BakeShot:
    name: str
    stage: Path
    frame: float
    all_meshes: bool = False
    width: int = 640


#: the bundled shirt at W = 0.28, where issues 23 and 56 set their bars on the baked maps
#: (stages/shirt_w028.usda says why the sample's own W is 0.1)
SHIRT_W028 = Path(__file__).resolve().parent / "stages" / "shirt_w028.usda"
#: issue 23's decoded-normal shot: the shirt's elbow at frame 24 (the angle tests)
ELBOW_SHOT = BakeShot("shirt", SHIRT_W028, 24)

#: issue 23's shots: the shirt's elbow and cuff, pull's sheet, CesiumMan's body, as bundled
MAP_SHOTS = (
    BakeShot("shirt", SAMPLES / "shirt.usda", 24),
    BakeShot("pull", SAMPLES / "pull.usda", 24),
    BakeShot("CesiumMan", CORPUS / "usd-wg" / "CesiumMan.usdz", 24, all_meshes=True,
             width=960),
)


@dataclass
class Prepared:
    """A shot's stage with flat textures and a camera both renderers look through."""

    shot: BakeShot
    stage: Path
    camera: str
    folder: Path
    #: usdview's head-light on: the stage has no lights of its own
    camera_light: bool

    def base(self, label: str) -> Path:
        return self.folder / f"{self.shot.name}.{label}"

    def meshes(self) -> tuple[str, ...]:
        return ("--all-meshes",) if self.shot.all_meshes else ()

    def render(self, stage, out, *extra) -> Path:
        _usdwrinkle("render", stage, out, "--frames", f"{self.shot.frame:g}", "--width",
                    self.shot.width, "--camera", self.camera, "--quiet", *self.meshes(),
                    *extra)
        return Path(out)

    def bake(self, out, *extra) -> Path:
        _usdwrinkle("bake", self.stage, out, "--frames", f"{self.shot.frame:g}", "--quiet",
                    *self.meshes(), *extra)
        return Path(out)

    def storm_job(self, stage, out, **extra) -> dict:
        return {"stage": str(stage), "camera": self.camera, "frame": self.shot.frame,
                "width": self.shot.width, "out": str(out),
                "camera_light": self.camera_light, **extra}


def prepare(shot: BakeShot, folder: Path, slack: float | None = 0.0) -> Prepared:
    """The shot framed, flat-textured and with the measured controls (``slack`` None:
    the fallback slack)."""
    folder.mkdir(parents=True, exist_ok=True)
    framed, camera = shared_camera(shot.stage.resolve(), folder)
    stage, layer = over_layer(Path(framed).resolve(), folder / f"{shot.name}.flat.usda")
    flat_textures(stage, folder)
    measured_controls(stage, mesh_width=shot.all_meshes, slack=slack)
    layer.Save()
    return Prepared(shot, Path(layer.realPath), camera, folder, not has_lights(shot.stage))


def measured_controls(stage, mesh_width: bool, slack: float | None = 0.0) -> None:
    """The controls these comparisons were measured with (issues 23 and 24), authored on
    every mesh of the over layer: wrinkle:slack = ``slack`` (0, the paper's amplitude law,
    unless told: the wrinkles then cover most of each mesh; with the default slack,
    compression under 6% draws none, and the per-tile and colour-ramp comparisons lose
    their signal; None leaves the fallback, as test_realclients' Storm normals check), and with
    ``mesh_width`` (a corpus asset wrinkled with --all-meshes) wrinkle:cloth = "mesh",
    4 x its mean edge: CesiumMan, in metres, would get cotton's 3.4-9.5 cm folds, finer
    than these frames resolve. The renderers' agreement is what is tested, not the defaults
    (docs/physics.md tests those)."""
    from pxr import Sdf, UsdGeom

    from usdwrinkle.usd import schema

    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.Mesh):
            if slack is not None:
                prim.CreateAttribute(schema.SLACK, Sdf.ValueTypeNames.Float).Set(slack)
            if mesh_width:
                prim.CreateAttribute(schema.CLOTH, Sdf.ValueTypeNames.Token).Set(
                    schema.MESH_CLOTH)


def grey(path) -> tuple[np.ndarray, np.ndarray]:
    """(mean of the sRGB codes, fully covered) of an 8-bit RGBA image."""
    rgba = read_rgba8(path).astype(np.float64)
    return rgba[..., :3].mean(axis=2), rgba[..., 3] == 255


@dataclass
class Contribution:
    """Two renderers' wrinkle contributions over the pixels all four images cover."""

    ours: np.ndarray    # (h, w) in 8-bit codes
    theirs: np.ndarray
    mask: np.ndarray    # (h, w) bool

    def correlation(self, where: np.ndarray | None = None) -> float:
        mask = self.mask if where is None else self.mask & where
        return float(np.corrcoef(self.ours[mask], self.theirs[mask])[0, 1])

    def high_pass_correlation(self, radius: int = 3) -> float:
        """correlation() of what a (2 radius + 1)² box blur leaves (both images): the fine
        part of the contribution, where a texture's pattern moving with the folds shows
        (the plaid's lines, 2-4 px apart at 960 px), and the shading's broad bands do
        not."""
        def fine(image):
            inside = np.where(self.mask, image, 0.0)
            padded = np.pad(inside, radius, mode="edge")
            blurred = np.zeros_like(inside)
            for dy in range(2 * radius + 1):
                for dx in range(2 * radius + 1):
                    blurred += padded[dy:dy + inside.shape[0], dx:dx + inside.shape[1]]
            return inside - blurred / (2 * radius + 1) ** 2

        a, b = fine(self.ours)[self.mask], fine(self.theirs)[self.mask]
        return float(np.corrcoef(a, b)[0, 1])

    def tiles(self, n: int = 4, min_pixels: int = 400, min_std: float = 3.0,
              min_share: float = 0.05):
        """{(row, column): (correlation, pixels)} over an n x n grid on the covered
        pixels' bound, for each tile with ``min_pixels`` and wrinkles that show (our
        contribution's standard deviation at least ``min_std`` codes, and at least
        ``min_std`` codes on ``min_share`` of its pixels: a tile of a bare head with a rim
        of folds scores Storm's 8-bit flat normal map and silhouette ring, measured 0.89
        when 2.5% of CesiumMan's head tile showed its shoulders' folds; on 2026-12-07
        5.5% do, and it scores 0.954: docs/physics.md, "What that tile is")."""
        ys, xs = np.nonzero(self.mask)
        y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
        result = {}
        for i in range(n):
            for j in range(n):
                tile = np.zeros_like(self.mask)
                tile[y0 + (y1 - y0) * i // n:y0 + (y1 - y0) * (i + 1) // n,
                     x0 + (x1 - x0) * j // n:x0 + (x1 - x0) * (j + 1) // n] = True
                tile &= self.mask
                count = int(np.count_nonzero(tile))
                showing = np.count_nonzero(tile & (np.abs(self.ours) >= min_std))
                if count >= min_pixels and self.ours[tile].std() >= min_std and \
                        showing >= min_share * count:
                    result[(i, j)] = (self.correlation(tile), count)
        return result


def contribution(ours_wrinkled, ours_plain, theirs_wrinkled, theirs_plain) -> Contribution:
    ow, m1 = grey(ours_wrinkled)
    op, m2 = grey(ours_plain)
    tw, m3 = grey(theirs_wrinkled)
    tp, m4 = grey(theirs_plain)
    return Contribution(ow - op, tw - tp, erode(m1 & m2 & m3 & m4))


@dataclass
class BakeViews:
    """One shot's renders: usdwrinkle's, and Storm's of each bake output."""

    prepared: Prepared
    images: dict  # label -> path

    def maps(self) -> Contribution:
        i = self.images
        return contribution(i["ours"], i["ours_plain"], i["storm_maps"], i["storm_points"])

    def horizon_turned(self, grow: int = 1) -> np.ndarray:
        """horizon_turned() of usdwrinkle's shading normals (its ours_aovs.exr, which
        bake_views(display_color=True) renders) through the shot's camera, grown by
        ``grow`` pixels."""
        normals, covered = our_normals(self.images["ours_aovs"])
        p = self.prepared
        return horizon_turned(normals, covered,
                              view_directions(p.stage, p.camera, p.shot.frame, normals.shape),
                              grow)

    def grazing(self, cosine: float) -> np.ndarray:
        """(h, w) bool: the covered pixels where the coarse surface (usdwrinkle's shading
        normals without wrinkles, its ours_plain_aovs.exr) faces the eye at a cosine under
        ``cosine``: a view that grazes the cloth."""
        normals, covered = our_normals(self.images["ours_plain_aovs"])
        p = self.prepared
        eye = view_directions(p.stage, p.camera, p.shot.frame, normals.shape)
        return covered & (np.sum(normals * eye, axis=-1) < cosine)


def map_set_flags(tangent_space: str | None, layout: str | None = None) -> tuple:
    """bake's flags for one map set in ``tangent_space`` and ``layout``; with neither, none
    (the default bake's set per material purpose)."""
    return (("--tangent-space", tangent_space) if tangent_space else ()) + \
        (("--map-layout", layout) if layout else ())


def bake_views(shot: BakeShot, folder: Path, map_size: int = 2048,
               geometry: bool = True, display_color: bool = False,
               tangent_space: str | None = None) -> BakeViews:
    """Render ``shot`` through usdwrinkle and its bake outputs through Storm (the maps
    in ``tangent_space``; None: bake's default)."""
    p = prepare(shot, folder)
    images = {"ours": p.render(p.stage, p.base("ours.png")),
              "ours_plain": p.render(p.stage, p.base("ours_plain.png"), "--no-wrinkles")}
    layers = {"maps": p.bake(p.base("maps.usda"), "--maps", "normal", "--map-size",
                             map_size, *map_set_flags(tangent_space)),
              "points": p.bake(p.base("points.usda"), "--with-points")}
    purposes = {}
    if geometry:
        layers["geometry"] = p.bake(p.base("geometry.usda"), "--geometry", "--with-points")
        purposes["geometry"] = ["default", "render"]
        # usdwrinkle draws the default and render purposes: the displaced mesh
        images["ours_geometry"] = p.render(layers["geometry"], p.base("ours_geometry.png"),
                                           "--no-wrinkles")
    if display_color:
        layers["display"] = p.bake(p.base("display.usda"), "--display-color", "amplitude",
                                   "--with-points")
        images["ours_aovs"] = p.render(p.stage, p.base("ours_aovs.exr"))
        # the coarse surface's normals (BakeViews.grazing)
        images["ours_plain_aovs"] = p.render(p.stage, p.base("ours_plain_aovs.exr"),
                                             "--no-wrinkles")
        # the amplitude of regular folds: what a per-vertex layer can hold (irregular
        # folds vary within a fold, by up to 2x; display_ramp_order)
        images["ours_aovs_regular"] = p.render(regular_layer(p.stage, p.base("regular.usda")),
                                               p.base("ours_aovs_regular.exr"))
        # usdwrinkle's render of that layer (its preview material reads displayColor)
        images["ours_display"] = p.render(layers["display"], p.base("ours_display.png"),
                                          "--no-wrinkles")
    jobs = []
    for label, layer in layers.items():
        images[f"storm_{label}"] = p.base(f"storm_{label}.png")
        jobs.append(p.storm_job(layer, images[f"storm_{label}"],
                                **({"purposes": purposes[label]} if label in purposes
                                   else {})))
    failed = {k: v for k, v in storm(jobs).items() if v != "ok"}
    if failed:
        raise RuntimeError(f"Storm could not render {shot.name}: {failed}")
    return BakeViews(p, images)


def hue(rgb: np.ndarray) -> np.ndarray:
    """HSV hue in [0, 1) of (..., 3) colours; lighting that scales a colour keeps it."""
    r, g, b = np.moveaxis(rgb.astype(np.float64), -1, 0)
    top, bottom = rgb.max(axis=-1), rgb.min(axis=-1)
    span = np.maximum(top - bottom, 1e-9)
    h = np.where(top == r, (g - b) / span % 6, np.where(top == g, (b - r) / span + 2,
                                                         (r - g) / span + 4))
    return h / 6.0


def rank_correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Spearman's rank correlation (ties broken by order: the images' values are dense)."""
    ranks = [np.argsort(np.argsort(x, kind="stable")).astype(np.float64) for x in (a, b)]
    return float(np.corrcoef(*ranks)[0, 1])


def regular_layer(stage_path, target) -> Path:
    """A layer over ``stage_path`` with wrinkle:irregularity 0 on every mesh (the same
    waves, drawn regular; every mesh, since a shot may wrinkle all of them, --all-meshes,
    where none has WrinkleAPI applied)."""
    from pxr import Sdf, UsdGeom

    from usdwrinkle.usd import schema

    stage, layer = over_layer(Path(stage_path).resolve(), Path(target))
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.Mesh):
            prim.CreateAttribute(schema.IRREGULARITY, Sdf.ValueTypeNames.Float).Set(0.0)
    layer.Save()
    return Path(layer.realPath)


def display_ramp_order(views: BakeViews) -> tuple[float, int]:
    """(rank correlation between the hue Storm shows of the display-colour layer and the
    wrinkle amplitude usdwrinkle renders for regular folds (the EXR's wrinkle.amplitude of
    the stage with wrinkle:irregularity 0: the layer holds one amplitude per vertex, and
    irregular folds vary within a fold, which it cannot hold), pixels compared). The ramp
    is viridis, whose hue falls from purple to yellow as the amplitude rises: close to -1
    when Storm shows the amplitude the layer holds."""
    import OpenEXR

    rgba = read_rgba8(views.images["storm_display"])
    channels = OpenEXR.File(str(views.images["ours_aovs_regular"])).channels()
    amplitude = np.asarray(channels["wrinkle.amplitude"].pixels, np.float64)
    covered = np.asarray(channels["RGBA"].pixels, np.float64)[..., 3] >= 0.999
    mask = erode(covered & (rgba[..., 3] == 255)) & np.isfinite(amplitude)
    saturated = rgba[..., :3].max(axis=-1).astype(int) - rgba[..., :3].min(axis=-1) > 12
    mask &= saturated  # hue is defined
    return rank_correlation(hue(rgba[..., :3])[mask], amplitude[mask]), int(mask.sum())


#: photometric stereo's light directions (the direction light travels is -axis)
AXES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")


def lit_by(stage_path: Path, axis: str, target: Path) -> Path:
    """A layer over ``stage_path`` whose only light is a distant light from ``axis``
    (the stage's lights deactivated)."""
    from pxr import Gf, UsdGeom, UsdLux

    stage, layer = over_layer(stage_path, target)
    for prim in [p for p in stage.Traverse() if p.HasAPI(UsdLux.LightAPI)]:
        prim.SetActive(False)
    light = UsdLux.DistantLight.Define(stage, "/PhotometricLight")
    light.CreateIntensityAttr(float(np.pi))
    light.CreateNormalizeAttr(True)  # irradiance pi: a white diffuse surface reads n.l
    # a distant light shines along its -Z: turn -Z to point against ``axis``
    toward = Gf.Vec3d(0, 0, 0)
    toward["XYZ".index(axis[1])] = 1.0 if axis[0] == "+" else -1.0
    rotation = Gf.Rotation(Gf.Vec3d(0, 0, 1), toward)
    UsdGeom.Xformable(light).AddTransformOp().Set(Gf.Matrix4d().SetRotate(rotation))
    layer.Save()
    return target


def decoded_normals(images: dict) -> tuple[np.ndarray, np.ndarray]:
    """(unit normals (h, w, 3), where all six images cover and the normal is defined)
    from {axis: linear EXR path}."""
    import OpenEXR

    def luminance(path):
        channels = OpenEXR.File(str(path)).channels()
        rgba = channels["RGBA"].pixels if "RGBA" in channels else np.dstack(
            [channels[c].pixels for c in "RGBA"])
        rgba = np.asarray(rgba, np.float64)
        return rgba[..., :3].mean(axis=2), rgba[..., 3] >= 0.999

    values = {axis: luminance(path) for axis, path in images.items()}
    n = np.dstack([values[f"+{a}"][0] - values[f"-{a}"][0] for a in "XYZ"])
    covered = np.logical_and.reduce([m for _, m in values.values()])
    length = np.linalg.norm(n, axis=2)
    ok = erode(covered) & (length > 1e-4)
    return n / np.maximum(length, 1e-12)[..., None], ok


def normal_views(shot: BakeShot, folder: Path, map_size: int = 2048,
                 tangent_space: str | None = "triangle", slack: float | None = 0.0,
                 layout: str | None = "asset", map_format: str = "png",
                 shade_samples: bool = True, memo: dict | None = None) -> dict:
    """{renderer: (normals, mask)} for usdwrinkle's render (``shade_samples`` False: render
    --no-shade-samples) and Storm's maps layer (its normal maps in ``tangent_space``,
    --map-layout ``layout`` (both None: the default bake, whose preview set Storm
    shows) and --map-format ``map_format``), each decoded by photometric stereo.
    ``memo``: a dict that keeps each side's decoded normals by what they depend on
    (usdwrinkle's on the shot, the slack and the shading; Storm's on the shot, the slack
    and the bake's options), so that cases which share a side render it once (both
    renderers draw the same input to the same pixels every time)."""
    memo = {} if memo is None else memo
    ours_key = ("usdwrinkle", shot, slack, shade_samples)
    storm_key = ("storm", shot, slack, map_size, tangent_space, layout, map_format)
    if ours_key in memo and storm_key in memo:
        return {"usdwrinkle": memo[ours_key], "storm": memo[storm_key]}
    p = prepare(shot, folder, slack)
    shading = () if shade_samples else ("--no-shade-samples",)
    tags = {axis: axis.replace("+", "p").replace("-", "m") for axis in AXES}
    if ours_key not in memo:
        ours = {axis: p.render(lit_by(p.stage, axis, p.base(f"lit{tag}.usda")),
                               p.base(f"ours_{tag}.exr"), *shading)
                for axis, tag in tags.items()}
        # where the draw turned a normal to its horizon, which the maps cannot, left out
        normals = decoded_normals(ours)
        memo[ours_key] = without_turned(normals, view_directions(
            p.stage, p.camera, shot.frame, normals[0].shape))
    if storm_key not in memo:
        maps = p.bake(p.base("maps.usda"), "--maps", "normal", "--map-size", map_size,
                      *map_set_flags(tangent_space, layout), "--map-format", map_format)
        theirs, jobs = {}, []
        for axis, tag in tags.items():
            theirs[axis] = p.base(f"storm_{tag}.exr")
            jobs.append({**p.storm_job(lit_by(maps, axis, p.base(f"maps_lit{tag}.usda")),
                                       theirs[axis]), "camera_light": False})
        failed = {k: v for k, v in storm(jobs).items() if v != "ok"}
        if failed:
            raise RuntimeError(f"Storm could not render {shot.name}: {failed}")
        memo[storm_key] = decoded_normals(theirs)
    return {"usdwrinkle": memo[ours_key], "storm": memo[storm_key]}


def angles(a, b) -> tuple[np.ndarray, np.ndarray]:
    """(degrees between two normal images, where both are defined)."""
    (na, ma), (nb, mb) = a, b
    mask = ma & mb
    cosine = np.clip(np.sum(na * nb, axis=2), -1, 1)
    return np.degrees(np.arccos(cosine)), mask


def our_normals(path) -> tuple[np.ndarray, np.ndarray]:
    """(world-space shading normals, fully covered) from usdwrinkle's EXR (N.X, N.Y, N.Z)."""
    import OpenEXR

    channels = OpenEXR.File(str(path)).channels()
    n = np.dstack([channels[f"N.{c}"].pixels for c in "XYZ"]).astype(np.float64)
    alpha = np.asarray(channels["RGBA"].pixels, np.float64)[..., 3]
    return _unit(n), erode(alpha >= 0.999)


def blender_normals(path, up_axis: str, layer: str = "Normal") -> tuple[np.ndarray, np.ndarray]:
    """(shading normals in the stage's axes, fully covered) from Blender's multilayer EXR
    (its ``layer``: the Normal pass, XYZ, or the Decoded AOV, RGB; world space, Z up; the
    importer turned a Y-up stage by +90 degrees about X, which is undone here)."""
    import OpenEXR

    parts = {part.name(): part for part in OpenEXR.File(str(path)).parts}
    channels = parts[f"ViewLayer.{layer}"].channels
    if layer == "Normal":
        n = np.dstack([channels[f"ViewLayer.Normal.{c}"].pixels for c in "XYZ"])
    else:  # the binding groups an AOV's RGB(A) into one channel
        n = np.asarray(channels[f"ViewLayer.{layer}"].pixels)[..., :3]
    n = n.astype(np.float64)
    combined = parts["ViewLayer.Combined"].channels["ViewLayer.Combined"].pixels
    if up_axis == "Y":
        n = np.dstack([n[..., 0], n[..., 2], -n[..., 1]])
    return _unit(n), erode(np.asarray(combined)[..., 3] >= 0.999)


def _unit(n: np.ndarray) -> np.ndarray:
    return n / np.maximum(np.linalg.norm(n, axis=2), 1e-12)[..., None]


def blender_backfacing(path) -> np.ndarray:
    """The share of each pixel's samples that hit a back face, from Blender's multilayer
    EXR (its "Backfacing" AOV: cycles_client's ``backfacing`` job key)."""
    import OpenEXR

    parts = {part.name(): part for part in OpenEXR.File(str(path)).parts}
    channels = parts["ViewLayer.Backfacing"].channels
    return np.asarray(channels["ViewLayer.Backfacing.X"].pixels, np.float64)


def front_angles(a, b, *backfacing: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """angles() over the pixels whose every sample hit a front face in each of the
    ``backfacing`` shares (blender_backfacing; a pixel on a silhouette between front and
    back faces is in neither): renderers write a back face's normal-mapped normal (the
    inside of a sleeve) each its own way (cycles_back_face)."""
    if not backfacing:
        raise ValueError("front_angles needs a renderer's backfacing share")
    degrees, mask = angles(a, b)
    for share in backfacing:
        mask = mask & (share <= 0.001)
    return degrees, mask


def back_angles(a, b, backfacing: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """angles() over the pixels whose every sample hit a back face."""
    degrees, mask = angles(a, b)
    return degrees, mask & (backfacing >= 0.999)


def cycles_back_face(n: np.ndarray, facing: np.ndarray) -> np.ndarray:
    """What Cycles shades a back face with, from usdwrinkle's normal ``n`` there and the
    unwrinkled normal ``facing`` (both turned toward the viewer). Storm's preview surface
    (ComputeTBNMatrix) and usdwrinkle build a double-sided back face's frame from its
    tangent, its bitangent and the turned normal, so a normal map's tilt reads the same
    from both sides; Cycles' normal-map node decodes in the front face's frame and
    negates the result whole (svm_node_normal_map), which turns the tilt by 180 degrees
    about the normal: measured on the shirt's cuff, where the sleeve's inside shows,
    Cycles' decoded normal is ours so turned within 0.02 degrees at the median."""
    z = np.sum(n * facing, axis=-1, keepdims=True)
    return _unit(2.0 * z * facing - n)


def horizon_turned(normals: np.ndarray, covered: np.ndarray,
                   towards_eye: np.ndarray, grow: int = 1) -> np.ndarray:
    """(h, w) bool: the covered pixels where usdwrinkle's draw turned a bent normal back
    to its horizon (contract.HORIZON_COSINE: a seen point faces the eye), grown by
    ``grow`` pixels (4-neighbourhood; one for the antialiasing). A normal map is the same
    for every view and cannot: there Storm shades the normal that faces away, and Cycles
    decodes it (then clamps its reflection: cycles_reflection_clamp)."""
    from usdwrinkle.method.contract import HORIZON_COSINE

    turned = covered & (np.sum(normals * towards_eye, axis=-1) < HORIZON_COSINE + 0.02)
    return ~erode(~turned, grow)  # grown as erode shrinks


def without_turned(normals: tuple, towards_eye: np.ndarray) -> tuple:
    """(normals, mask) from our_normals with the pixels horizon_turned() left out."""
    n, mask = normals
    return n, mask & ~horizon_turned(n, mask, towards_eye)


def view_directions(stage_path: Path, camera: str, frame: float, shape) -> np.ndarray:
    """(h, w, 3) unit world-space directions from each pixel's surface toward the camera
    (row 0 at the top), through ``camera`` of ``stage_path`` at ``frame`` as usdwrinkle
    frames it for an image of that shape (scene.camera.towards_eye)."""
    from pxr import Usd

    from usdwrinkle.scene.camera import towards_eye, usd_camera

    stage = Usd.Stage.Open(str(stage_path))
    height, width = shape[:2]
    record = usd_camera(stage.GetPrimAtPath(camera), Usd.TimeCode(frame), width / height)
    return towards_eye(record, width, height)


def cycles_reflection_clamp(n: np.ndarray, ng: np.ndarray, i: np.ndarray) -> np.ndarray:
    """Cycles' ensure_valid_specular_reflection (kernel/closure/bsdf_util.h), which its
    normal-map node output goes through before shading and the Normal pass: a shading
    normal whose mirror reflection of the view direction ``i`` would fall below the
    surface ``ng`` is tilted back toward ``ng`` until it does not. A normal tilted more
    than 45 degrees from ``ng`` seen head-on is clamped, so steep normal-map wrinkles show
    shallower in Cycles than in usdwrinkle, Storm or the geometry layer."""
    dot = lambda a, b: np.sum(a * b, axis=-1, keepdims=True)  # noqa: E731
    reflected = 2.0 * dot(n, i) * n - i
    iz = np.maximum(dot(i, ng), 0.0)
    threshold = np.minimum(0.9 * iz, 0.01)
    x = _unit(n - dot(n, ng) * ng)
    ix = dot(i, x)
    a = np.maximum(ix ** 2 + iz ** 2, 1e-12)
    b = 2.0 * (a + iz * threshold)
    c = (threshold + iz) ** 2
    root = np.sqrt(np.maximum(b ** 2 - 4.0 * a * c, 0.0))
    nz2 = np.clip(np.where(ix < 0, 0.25 * (b + root) / a, 0.25 * (b - root) / a), 0.0, 1.0)
    clamped = np.sqrt(1.0 - nz2) * x + np.sqrt(nz2) * ng
    return np.where(dot(ng, reflected) >= threshold, n, clamped)


def cycles_views(shot: BakeShot, folder: Path, map_size: int = 2048,
                 tangent_space: str | None = "triangle") -> dict:
    """{output: (usdwrinkle's normals, Cycles' normals)} for the maps layer (its normal
    maps in ``tangent_space``, None: the default bake, whose all-purpose set Blender
    imports; against usdwrinkle's wrinkled render) and the geometry
    layer (against usdwrinkle's render of that layer), from each renderer's world-space
    normal AOV; also "decoded": Cycles' decoded map normal (its Normal Map nodes' output)
    against usdwrinkle's, "decoded_per_pixel": the same against usdwrinkle's render
    --no-shade-samples, "plain": usdwrinkle's unwrinkled normals, "backfacing": {output:
    the share of each pixel's samples on a back face in Cycles' render of it}
    (front_angles) and "view": the directions toward the camera (for
    cycles_reflection_clamp). Cycles imports the layers through
    Blender's USD importer (coarse meshes: no subdivision, as usdview's default
    complexity), the render purpose on for the geometry layer."""
    from pxr import Usd, UsdGeom

    p = prepare(shot, folder)
    up_axis = UsdGeom.GetStageUpAxis(Usd.Stage.Open(str(p.stage)))
    layers = {"maps": p.bake(p.base("maps.usda"), "--maps", "normal", "--map-size",
                             map_size, *map_set_flags(tangent_space)),
              "geometry": p.bake(p.base("geometry.usda"), "--geometry", "--with-points")}
    ours = {"maps": p.render(p.stage, p.base("ours.exr")),
            "geometry": p.render(layers["geometry"], p.base("ours_geometry.exr"),
                                 "--no-wrinkles")}
    plain = our_normals(p.render(p.stage, p.base("ours_plain.exr"), "--no-wrinkles"))
    height = our_normals(ours["maps"])[1].shape[0]
    jobs = [{"stage": str(layers[k]), "camera": p.camera, "frame": shot.frame,
             "width": shot.width, "height": height, "out": str(p.base(f"cycles_{k}.exr")),
             "purposes": ["default", "render"] if k == "geometry" else None,
             "decoded": k == "maps", "backfacing": True}
            for k in layers]
    failed = {k: v for k, v in cycles(jobs).items() if v != "ok"}
    if failed:
        raise RuntimeError(f"Cycles could not render {shot.name}: {failed}")
    views = {k: (our_normals(ours[k]), blender_normals(p.base(f"cycles_{k}.exr"), up_axis))
             for k in layers}
    towards_eye = view_directions(p.stage, p.camera, shot.frame, plain[0].shape)
    decoded = blender_normals(p.base("cycles_maps.exr"), up_axis, "Decoded")
    # the decoded map against our normals where the draw did not turn them to the horizon
    views["decoded"] = (without_turned(views["maps"][0], towards_eye), decoded)
    views["decoded_per_pixel"] = (without_turned(our_normals(p.render(
        p.stage, p.base("ours_per_pixel.exr"), "--no-shade-samples")), towards_eye), decoded)
    views["plain"] = plain
    views["backfacing"] = {k: blender_backfacing(p.base(f"cycles_{k}.exr")) for k in layers}
    views["view"] = towards_eye
    return views


#: issue 56's shot: the plaid shirt's sleeve at frame 24, 960 px, its textures as they are,
#: at the W its bars were set on (0.28: stages/shirt_w028.usda says why; the demo's 0.1 is
#: measured by ``python -m realclients.figure --texture ... --demo-width``)
TEXTURE_SHOT = BakeShot("shirt", SHIRT_W028, 24, width=960)
DEMO_TEXTURE_SHOT = replace(TEXTURE_SHOT, stage=SAMPLES / "shirt.usda")


def turned_camera(stage, camera: str, frame: float, degrees: float, path: str) -> str:
    """Define ``path`` in ``stage``'s edit target: ``camera`` turned by ``degrees`` about
    the stage's up axis through the centre of the wrinkled meshes' bounds at ``frame``
    (the camera the bake never saw); returns ``path``."""
    from pxr import Gf, Usd, UsdGeom

    time = Usd.TimeCode(frame)
    source = UsdGeom.Camera(stage.GetPrimAtPath(camera))
    cache = UsdGeom.BBoxCache(time, [UsdGeom.Tokens.default_, UsdGeom.Tokens.render])
    centre = cache.ComputeWorldBound(stage.GetPseudoRoot()).ComputeAlignedRange().GetMidpoint()
    up = Gf.Vec3d(0, 1, 0) if UsdGeom.GetStageUpAxis(stage) == "Y" else Gf.Vec3d(0, 0, 1)
    turn = Gf.Matrix4d().SetTranslate(-centre) * \
        Gf.Matrix4d().SetRotate(Gf.Rotation(up, degrees)) * Gf.Matrix4d().SetTranslate(centre)
    gf_camera = source.GetCamera(time)
    gf_camera.transform = gf_camera.transform * turn
    turned = UsdGeom.Camera.Define(stage, path)
    turned.SetFromCamera(gf_camera, Usd.TimeCode.Default())
    return path


def upper_centre(points_layer: Path, frame: float) -> tuple:
    """The world-space centre of the bounds of the upper half (along the stage's up axis)
    of the posed points in a --with-points layer at ``frame``: on the shirt, the upper arm
    with its cuff, where the folds are."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(points_layer))
    time = Usd.TimeCode(frame)
    axis = 1 if UsdGeom.GetStageUpAxis(stage) == "Y" else 2
    points = []
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.Mesh):
            local = np.asarray(UsdGeom.Mesh(prim).GetPointsAttr().Get(time), np.float64)
            matrix = np.asarray(UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(time))
            points.append(local @ matrix[:3, :3] + matrix[3, :3])
    points = np.concatenate(points)
    middle = (points[:, axis].min() + points[:, axis].max()) / 2.0
    upper = points[points[:, axis] >= middle]
    return tuple((upper.min(axis=0) + upper.max(axis=0)) / 2.0)


def zoomed_camera(stage, camera: str, frame: float, zoom: float, path: str,
                  centre: tuple) -> str:
    """Define ``path`` in ``stage``'s edit target: ``camera`` with its apertures divided by
    ``zoom`` and its aperture offset moved so that the world point ``centre`` is the
    image's centre (a render ``zoom`` times smaller then shows that region at the
    original's pixel size); returns ``path``."""
    from pxr import Gf, Usd, UsdGeom

    time = Usd.TimeCode(frame)
    gf_camera = UsdGeom.Camera(stage.GetPrimAtPath(camera)).GetCamera(time)
    ndc = gf_camera.frustum.ComputeViewMatrix() * gf_camera.frustum.ComputeProjectionMatrix()
    x, y, _ = ndc.Transform(Gf.Vec3d(centre))
    width, height = gf_camera.horizontalAperture, gf_camera.verticalAperture
    gf_camera.horizontalApertureOffset += x * width / 2.0
    gf_camera.verticalApertureOffset += y * height / 2.0
    gf_camera.horizontalAperture = width / zoom
    gf_camera.verticalAperture = height / zoom
    zoomed = UsdGeom.Camera.Define(stage, path)
    zoomed.SetFromCamera(gf_camera, Usd.TimeCode.Default())
    return path


@dataclass
class TextureViews:
    """usdwrinkle's and the clients' renders of the texture shot, at the shot's camera and
    at each turned one: {degrees: {label: path}}; labels ours, ours_plain, and per client
    (storm, cycles, eevee) CLIENT_parallax (the maps layer with --maps normal,parallax:
    its MaterialX network; in Blender through the add-on), CLIENT_points (--with-points),
    storm_normal (--maps normal: the UsdPreviewSurface alone), storm_flat (the network
    without the wrinkles: unwrinkled_network; storm_parallax's baseline), cycles_stock
    (the parallax layer imported without the add-on: its UsdPreviewSurface)."""

    images: dict

    def contribution(self, degrees: float, label: str = "storm_parallax") -> Contribution:
        """The wrinkle contribution of ``label`` (minus its client's points render)
        against usdwrinkle's."""
        i = self.images[degrees]
        client = label.split("_")[0]
        plain = f"{client}_flat" if label == "storm_parallax" and f"{client}_flat" in i \
            else f"{client}_points"
        return contribution(i["ours"], i["ours_plain"], i[label], i[plain])


#: Blender's importer's light_intensity_scale: Cycles' renders of the samples at about
#: Storm's mean brightness (measured on the shirt; realclients.figure's panels too)
CYCLES_LIGHT_SCALE = 0.08
#: the strength of Cycles' head-light (a sun along the view) for a stage without lights
CYCLES_HEAD_LIGHT = 3.0

#: usdwrinkle's Blender add-on (Cycles' and EEVEE's import of the MaterialX network)
BLENDER_ADDON = Path(__file__).resolve().parents[1] / "src" / "usdwrinkle" / "blender" / \
    "usdwrinkle_blender.py"


def unwrinkled_network(stage) -> int:
    """In ``stage``'s edit target: every wrinkle material's MaterialX network with the
    wrinkles taken out (the texture offset 0, the normal the renderer's own), so that a
    renderer draws the same shot through the same texture path without them: the baseline
    of its wrinkle contribution. Storm's UsdPreviewSurface filters textures otherwise than
    its MaterialX image node (measured: fine differences along the plaid's lines over the
    whole sleeve, wrinkled or not), which a baseline through the UsdPreviewSurface counted
    as wrinkles. Returns how many networks it changed."""
    from pxr import Sdf, UsdShade

    from usdwrinkle.maps.mtlx import PREFIX, SURFACE_OUTPUT

    changed = 0
    for prim in stage.Traverse():
        if not prim.IsA(UsdShade.Material) or not prim.GetAttribute(SURFACE_OUTPUT):
            continue
        offset = prim.GetChild(f"{PREFIX}Offset")
        surface = prim.GetChild(f"{PREFIX}Surface")
        if not offset or not surface:
            continue
        for name in ("inputs:in1", "inputs:in2"):
            attribute = offset.GetAttribute(name)
            attribute.SetConnections([])
            attribute.Set(0.0)
        normal = surface.GetAttribute("inputs:normal")
        normal.SetConnections([])
        normal.Set((0.0, 0.0, 1.0))  # tangent space: the renderer's own normal
        assert normal.GetTypeName() == Sdf.ValueTypeNames.Float3
        changed += 1
    return changed


def uniform_dome(stage, intensity: float = 1.0) -> None:
    """In ``stage``'s edit target: every light of the stage off, and one white dome light
    without a texture on. Under it, a surface's diffuse shading is its albedo whatever
    its normal, in every renderer, so that a comparison sees the texture where it moved
    and not how each renderer models lights (Cycles' Principled BSDF and sun lamps against
    UsdPreviewSurface's distant lights)."""
    from pxr import UsdLux

    for prim in stage.Traverse():
        if prim.HasAPI(UsdLux.LightAPI):
            prim.SetActive(False)
    dome = UsdLux.DomeLight.Define(stage, "/UniformDome")
    dome.CreateIntensityAttr(intensity)
    dome.CreateColorAttr((1.0, 1.0, 1.0))
    # Storm ignores a dome without a texture (tests/test_realclients.py): a white one
    folder = Path(stage.GetRootLayer().realPath).parent
    white = folder / "uniform_white.exr"
    if not white.exists():
        import OpenImageIO as oiio

        buf = oiio.ImageBuf(oiio.ImageSpec(16, 8, 3, oiio.FLOAT))
        oiio.ImageBufAlgo.fill(buf, (1.0, 1.0, 1.0))
        buf.write(str(white))
    dome.CreateTextureFileAttr(str(white))


def texture_views(folder: Path, turns=(0.0, 30.0), shot: BakeShot = TEXTURE_SHOT,
                  map_size: int = 2048, clients=("storm",), samples: int = 16,
                  lighting: str = "stage", zoom: float = 1.0,
                  storm_timeout: float = 600) -> TextureViews:
    """The texture deformation through Storm, Cycles and/or EEVEE (``clients``): the
    shot's layers baked once (no camera in them), each seen through the shot's camera
    turned by each of ``turns``. Storm: storm_parallax, storm_normal, storm_points
    (TextureViews). Cycles (through Blender's importer, ``samples`` per pixel, without
    shadows or inter-reflection, as usdwrinkle and Storm draw): cycles_parallax with the
    add-on (BLENDER_ADDON), cycles_stock the same layer without it (the
    UsdPreviewSurface), cycles_points the --with-points layer. EEVEE: eevee_parallax
    (with the add-on) and eevee_points. ``lighting``: "stage" (its own lights; Storm's
    without lights get usdview's head-light), or "dome" (uniform_dome()). ``zoom``: the
    frames are the shot's width divided by it, through a camera zoomed as much on the
    upper half of the posed meshes (upper_centre, zoomed_camera), so the texture's
    pattern keeps its pixel size at a fraction of the cost. ``storm_timeout``: seconds
    Storm's process may take for all the views."""
    folder.mkdir(parents=True, exist_ok=True)
    framed, camera = shared_camera(shot.stage.resolve(), folder)
    lit = has_lights(shot.stage) or lighting == "dome"
    width = int(round(shot.width / zoom))
    layers = {}
    size = ("--map-size", map_size)
    wanted = (("parallax", ("--maps", "normal,parallax", *size)),
              ("normal", ("--maps", "normal", *size)),
              ("points", ("--with-points",)))
    for label, flags in wanted:
        if label == "normal" and "storm" not in clients:
            continue
        layers[label] = folder / f"{shot.name}.{label}.usda"
        _usdwrinkle("bake", framed, layers[label], "--frames", f"{shot.frame:g}", "--quiet",
                    *flags)
    images, jobs, cycles_jobs = {}, [], []
    centre = upper_centre(layers["points"], shot.frame) if zoom != 1.0 else None
    for degrees in turns:
        tag = f"turn{degrees:g}"
        views = {}
        cameras = {}
        sources = [("source", Path(framed)), *layers.items()]
        if "storm" in clients:
            sources.append(("flat", layers["parallax"]))
        for label, stage_path in sources:
            stage, layer = over_layer(stage_path.resolve(),
                                      folder / f"{stage_path.stem}.{label}.{tag}.usda")
            if label == "flat":
                assert unwrinkled_network(stage) > 0
            cameras[label] = turned_camera(stage, camera, shot.frame, degrees, "/TurnedCamera") \
                if degrees else camera
            if zoom != 1.0:
                cameras[label] = zoomed_camera(stage, cameras[label], shot.frame, zoom,
                                               "/ZoomedCamera", centre)
            if lighting == "dome":
                uniform_dome(stage)
            layer.Save()
            views[label] = Path(layer.realPath)
        out = {}
        for name, extra in (("ours", ()), ("ours_plain", ("--no-wrinkles",))):
            out[name] = folder / f"{shot.name}.{tag}.{name}.png"
            _usdwrinkle("render", views["source"], out[name], "--frames", f"{shot.frame:g}",
                        "--width", width, "--camera", cameras["source"], "--quiet", *extra)
        height = read_rgba8(out["ours"]).shape[0]
        if "storm" in clients:
            for label in [*layers, "flat"]:
                out[f"storm_{label}"] = folder / f"{shot.name}.{tag}.storm_{label}.png"
                jobs.append({"stage": str(views[label]), "camera": cameras[label],
                             "frame": shot.frame, "width": width,
                             "out": str(out[f"storm_{label}"]), "camera_light": not lit})
        for client in ("cycles", "eevee"):
            if client not in clients:
                continue
            runs = (("parallax", "parallax", True), ("stock", "parallax", False),
                    ("points", "points", False))
            for name, label, addon in runs if client == "cycles" else runs[::2]:
                out[f"{client}_{name}"] = folder / f"{shot.name}.{tag}.{client}_{name}.png"
                cycles_jobs.append({"stage": str(views[label]), "camera": cameras[label],
                                    "frame": shot.frame, "width": width,
                                    "height": height, "samples": samples,
                                    "engine": "CYCLES" if client == "cycles"
                                    else "BLENDER_EEVEE",
                                    "out": str(out[f"{client}_{name}"]),
                                    "camera_light": None if lit else CYCLES_HEAD_LIGHT,
                                    "light_scale": CYCLES_LIGHT_SCALE, "shadows": False,
                                    "world": (1.0, 1.0, 1.0) if lighting == "dome" else None,
                                    "addon": str(BLENDER_ADDON) if addon else None})
        images[degrees] = out
    failed = {k: v for k, v in storm(jobs, storm_timeout).items() if v != "ok"} if jobs else {}
    if cycles_jobs:
        failed.update({k: v for k, v in cycles(cycles_jobs).items() if v != "ok"})
    if failed:
        raise RuntimeError(f"a client could not render {shot.name}: {failed}")
    return TextureViews(images)
