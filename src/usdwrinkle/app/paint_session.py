"""A paint session: one stage, the layer its strokes go to, the engine that draws it, the
brush, and undo. No Qt: the window (paint/window.py) is one front end on it, a test or a
script another.

Strokes are held here while the button is down and written straight into the engine's
GPU tables (``WrinkleEngine.preview_params``): the view shows the current frame at once,
computed from the kept wave state of the frame before it. When a stroke ends it is
authored through the WrinkleAPI (its checks apply) on the session's edit layer; the
engine's change tracking then restarts the phase history, so the refined frame is the one
``usdwrinkle render`` gives for the saved layer.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field, replace

import numpy as np
from pxr import Sdf, Usd, UsdGeom

from ..brush.stamp import DIRECTED, BrushSettings, Hit, PaintMesh, Stroke, clamp_unit, flood
from ..brush.view import OrbitCamera, pixel_ray, ray_triangles, vertex_normals
from ..layerinfo import copy_stage_info
from ..process.errors import UsdWrinkleError
from ..usd import schema

#: stamps along a drag lie at most this many pixels apart on screen (besides the brush's
#: spacing in radii): with a huge brush a short drag paints too (issue 57: at radius 6.37
#: a quarter radius was farther than an 80 px drag reached)
SCREEN_SPACING = 8.0

#: what the view draws the painted meshes in (View > Display): the material and the
#: wrinkles; the painted amount |q| on a ramp; the painted W on a ramp
DISPLAYS = ("shaded", "amount", "width")
#: the ramp's stops (weight-paint style, linear RGB): 0 blue, 0.25 cyan, 0.5 green,
#: 0.75 yellow, 1 red; an unpainted point (|q| = 0) in the amount display is grey
RAMP = np.array([[0.02, 0.05, 0.8], [0.0, 0.6, 0.7], [0.05, 0.7, 0.05], [0.9, 0.8, 0.0],
                 [0.85, 0.02, 0.02]])
UNPAINTED = (0.35, 0.35, 0.35)


def ramp(t) -> np.ndarray:
    """Colours of the display ramp at t in [0, 1] (clipped): (n, 3) linear RGB."""
    t = np.clip(np.asarray(t, np.float64), 0.0, 1.0) * (len(RAMP) - 1)
    i = np.minimum(np.floor(t).astype(np.int64), len(RAMP) - 2)
    f = (t - i)[:, None]
    return RAMP[i] * (1.0 - f) + RAMP[i + 1] * f


def display_colors(mesh: PaintMesh, display: str, reference_width: float) -> np.ndarray:
    """Per point of ``mesh``, its colour in ``display``: ``amount``, |q| on the ramp
    (grey where nothing is painted); ``width``, log2(W / reference_width) from -2 to 2
    on the ramp (green: the reference, the W control's value)."""
    if display == "amount":
        amount = np.linalg.norm(mesh.q.astype(np.float64), axis=1)
        colors = ramp(amount)
        colors[amount < 1e-3] = UNPAINTED
        return colors
    if display == "width":
        ratio = np.asarray(mesh.width, np.float64) / max(float(reference_width), 1e-30)
        return ramp(0.5 + np.log2(np.maximum(ratio, 1e-30)) / 4.0)
    raise UsdWrinkleError(f"display {display!r} is not one of {', '.join(DISPLAYS)}")


#: the live controls: WrinkleParams field -> (schema attribute, lowest, highest)
CONTROLS = {"width": (schema.WIDTH, 1e-4, None),
            "amplitude_scale": (schema.AMPLITUDE_SCALE, 0.0, 10.0),
            "slack": (schema.SLACK, 0.0, 0.95),
            "irregularity": (schema.IRREGULARITY, 0.0, schema.IRREGULARITY_MAX)}
CLOTH_PRESETS = (*schema.CLOTH_WIDTHS_M, schema.MESH_CLOTH)


@dataclass
class Edit:
    """One undoable step: a mesh's values before and after (q and width arrays, or one
    control)."""

    path: str
    name: str
    before: object
    after: object


@dataclass
class Quality:
    """How a frame is drawn: the full quality of ``usdwrinkle render``, or the reduced
    preview shown while the button is down."""

    samples: int = 4
    scale: float = 1.0

    @property
    def preview(self) -> bool:
        return self.samples == 1 and self.scale < 1.0


FULL = Quality(4, 1.0)
PREVIEW = Quality(1, 0.5)


@dataclass
class ViewImage:
    """What the view shows: RGBA codes (row 0 at the top), its size and camera."""

    pixels: np.ndarray
    width: int
    height: int
    camera: object
    quality: Quality
    frame: float
    seconds: float = 0.0
    timings: dict = field(default_factory=dict)


def open_paint_stage(stage_path: str, output: str | None):
    """(stage, edit layer, save path) for ``usdwrinkle paint STAGE [-o LAYER]``.

    - ``-o`` a layer that does not exist yet: a new layer that sublayers the stage (so it
      renders on its own) and holds the strokes as overs; written on save.
    - ``-o`` an existing layer whose layer stack holds the stage (an earlier paint
      layer): opened as the stage, strokes added to it.
    - ``-o`` any other existing layer: an overrides layer over the stage (as ``apply
      -o``); only it is written.
    - no ``-o``: the stage's root layer is edited and written in place.
    """
    from ..scene.inputs import open_layer, require_regular_file
    from ..scene.stage import open_stage

    stage = open_stage(stage_path)
    if output is None:
        root = stage.GetRootLayer()
        save = root.realPath if root.realPath and not root.realPath.lower().endswith(
            ".usdz") else None
        return stage, root, save
    from ..outputs.layers import check_layer_path

    check_layer_path(output)
    output = os.path.abspath(output)  # as named: USD anchors relative paths lexically
    folder = os.path.dirname(output)
    if not os.path.isdir(folder):
        raise UsdWrinkleError(f"`output` '{output}': the folder '{folder}' does not exist")
    _probe_writable(folder, output)
    if not os.path.exists(output):
        _refuse_input(stage, output)
        layer = Sdf.Layer.CreateAnonymous(".usda")
        # as the user named it: the saved layer names it relative to its own folder
        layer.subLayerPaths.append(os.path.abspath(stage_path))
        copy_stage_info(stage.GetRootLayer(), layer)
        if stage.GetRootLayer().HasDefaultPrim():
            layer.defaultPrim = stage.GetRootLayer().defaultPrim
        painted = Usd.Stage.Open(layer)
        return painted, layer, output
    require_regular_file(output, "paint layer")
    if not os.access(output, os.W_OK):
        raise UsdWrinkleError(f"`output` '{output}' is not writable")
    _refuse_input(stage, output)
    layer = open_layer(output, f"cannot open paint layer '{output}' (an existing file that "
                               "is not a USD layer?)")
    painted = Usd.Stage.Open(layer)
    wanted = os.path.realpath(stage.GetRootLayer().realPath or stage_path)
    stack = [os.path.realpath(item.realPath) for item in painted.GetLayerStack()
             if item.realPath]
    if wanted in stack:
        return painted, layer, output
    over = Usd.Stage.Open(stage.GetRootLayer(), layer)
    return over, layer, output


def _probe_writable(folder: str, output: str) -> None:
    """A file can be made in ``folder`` (tried: permissions alone do not say so for root,
    nor on a read-only file system)."""
    from ..outputs.atomic import probe_folder

    try:
        probe_folder(folder)
    except OSError as exc:
        raise UsdWrinkleError(f"`output` '{output}': the folder '{folder}' is not writable "
                              f"({exc.strerror})") from None


def _refuse_input(stage, output: str) -> None:
    """``-o`` means "leave my stage alone": never the stage or a file it reads, by any
    spelling (real path and inode: a symlink, a hard link, '..', '//')."""
    from ..scene.stage import stage_inputs

    if stage_inputs(stage).protects(output):
        raise UsdWrinkleError(f"`output` '{output}' is a file the stage reads (the stage, "
                              "one of its layers, a package or a texture); the paint layer "
                              "must be a new layer or an earlier paint layer (without "
                              "`output`, the stage's root layer is edited in place)")


class PaintSession:
    """Paints q and W on the wrinkled meshes of one stage.

    ``stage``: an open Usd.Stage whose edit target is ``layer`` (the strokes' layer);
    ``save_path``: where :meth:`save` writes ``layer`` (None: it lives in memory, as
    usdview's session layer does; :meth:`save` then only marks the session clean).
    """

    def __init__(self, stage: Usd.Stage, layer: Sdf.Layer, save_path: str | None = None,
                 prim: str | None = None, frame: float | None = None,
                 camera: str | None = None, all_meshes: bool = False, ctx=None,
                 history_cache: int = 32, in_memory: bool = False):
        from ..outputs.images import layout_for
        from ..usd.schema import require_schema
        from .options import ShotOptions
        from .shot import Shot

        require_schema()
        frame = check_frame(frame, stage)
        self.stage = stage
        self.layer = layer
        self.save_path = save_path
        #: the strokes' layer lives in memory (usdview's session layer): saving marks the
        #: session clean and writes nothing, unless a path is given
        self.in_memory = in_memory
        self.stage.SetEditTarget(Usd.EditTarget(layer))
        # the same shot as render and bake open (its units warnings too); the session
        # keeps more wave states, so that scrubbing back replays nothing
        self.engine = Shot(stage, ShotOptions(all_meshes=all_meshes)).start_engine(
            camera, ctx=ctx, history_cache=history_cache)
        self._layout = layout_for("view.png")
        paths = self.engine.wrinkled_paths
        if not paths:
            self.engine.release()
            raise UsdWrinkleError("no mesh has WrinkleAPI applied, so there is nothing to "
                                  "paint (pass `all_meshes` to paint every mesh)")
        if prim is not None and prim not in paths:
            self.engine.release()
            raise UsdWrinkleError(f"`prim` {prim} is not a wrinkled mesh of the stage "
                                  f"(wrinkled: {', '.join(paths)})")
        self.paths = [prim] if prim is not None else paths
        self.meshes = {path: self._paint_mesh(path) for path in self.paths}
        self.active = self.paths[0]
        frames = self.engine.frame_range()
        #: the frames the timeline offers ([default] for a stage without a time range)
        self.frames = [None if f is None else float(f) for f in frames]
        self.frame_range = (self.frames[0], self.frames[-1])
        end = self.frames[-1]
        self.frame = frame if frame is not None else end
        self.brush = BrushSettings(radius=0.1 * self._size(), width=float(
            np.median(self.meshes[self.active].width)))
        self.orbit: OrbitCamera | None = OrbitCamera(np.zeros(3), 1.0,
                                                     up_axis=UsdGeom.GetStageUpAxis(stage))
        #: look through the stage's camera (what render shows) instead of the orbit
        self.stage_camera = False
        #: what the meshes are drawn in (DISPLAYS; set_display)
        self.display = "shaded"
        #: the orbit moves with the meshes from frame to frame (View > Follow the mesh):
        #: its centre by as much as their box's centre moved
        self.follow = False
        #: draw the folds where the view ray meets them (View > Relief; render --relief)
        self.relief = False
        self._followed: tuple[float, np.ndarray] | None = None
        self.undo_stack: list[Edit] = []
        self.redo_stack: list[Edit] = []
        self._saved_at = 0
        self._stroke: Stroke | None = None
        self._stroke_before: tuple | None = None
        self._stroke_facing: np.ndarray | None = None
        #: per mesh: the side (1 front, -1 back) the last pick saw (see facing)
        self._sides: dict[str, float] = {}
        #: the drag's last sample: pixel x, y, its rest point, rest length per pixel
        self._stroke_sample: tuple | None = None
        #: the last stroke's rest-space direction (what comb floods along)
        self._last_stroke_direction: np.ndarray | None = None
        self._live: dict | None = None
        self._camera = None
        #: per mesh: its posed points (world) at the last drawn frame, read on first use
        self._posed: dict[str, np.ndarray] = {}
        self.last_frame: ViewImage | None = None
        self._framed = False
        #: the last stroke's stamp centres (rest space) and the vertices it touched
        self.stamp_centres: list[np.ndarray] = []
        self.last_touched = np.zeros(0, np.int64)

    # -- the meshes ---------------------------------------------------------------
    def _paint_mesh(self, path: str) -> PaintMesh:
        record = self.engine.meshes[path]
        return PaintMesh(path, record.rest_points, record.rest_normals,
                         record.topology.triangles, record.params.q, record.params.width)

    def _size(self) -> float:
        points = self.meshes[self.active].rest_points
        return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) or 1.0

    @property
    def mesh(self) -> PaintMesh:
        return self.meshes[self.active]

    @property
    def dirty(self) -> bool:
        """Strokes or control changes not saved yet."""
        return len(self.undo_stack) != self._saved_at

    def reload(self) -> None:
        """Re-read q and W from the stage (after an undo, or an outside edit)."""
        self.engine.pull_changes()
        for path in self.paths:
            self.meshes[path] = self._paint_mesh(path)

    # -- the view -------------------------------------------------------------------
    def frame_view(self, aspect: float) -> None:
        """Frame the orbit camera on the wrinkled meshes at the current frame (F)."""
        self._ensure_posed()
        boxes = [self.posed_points(path) for path in self.paths]
        lo = np.min([b.min(axis=0) for b in boxes], axis=0)
        hi = np.max([b.max(axis=0) for b in boxes], axis=0)
        self.orbit.frame(lo, hi, aspect)
        self._framed = True
        self._followed = (self.frame, 0.5 * (lo + hi))

    def _meshes_centre(self) -> np.ndarray:
        """The centre of the wrinkled meshes' box at the current frame (posed only: the
        skin pass, no wrinkles, which the frame's own compute then runs as always)."""
        self.engine.compute_frame(self.frame, wrinkles=False)
        boxes = [self.engine.posed_points(path) for path in self.paths]
        self._posed.clear()
        lo = np.min([b.min(axis=0) for b in boxes], axis=0)
        hi = np.max([b.max(axis=0) for b in boxes], axis=0)
        return 0.5 * (lo + hi)

    def set_display(self, display: str) -> None:
        """Draw the painted meshes in ``display`` (DISPLAYS) from the next frame on."""
        if display not in DISPLAYS:
            raise UsdWrinkleError(f"display {display!r} is not one of {', '.join(DISPLAYS)}")
        self.display = display
        if display == "shaded":
            for path in self.paths:
                self.engine.set_display_colors(path, None)

    def _apply_display(self) -> None:
        """The display's colours from the painted values as they are now (a stroke's
        preview included), uploaded before the frame is drawn."""
        if self.display == "shaded":
            return
        reference = self.control("width")
        for path in self.paths:
            self.engine.set_display_colors(
                path, display_colors(self.meshes[path], self.display, reference))

    def set_relief(self, on: bool) -> None:
        """Draw the folds where the view ray meets them, as ``render --relief`` does (the
        flanks that face away hide behind the crests), or on the coarse surface."""
        self.relief = bool(on)

    def set_follow(self, on: bool) -> None:
        """Follow the meshes from now on: the next frame frames them (as F does) and the
        view then moves with them; or stop (the view stays where it is)."""
        self.follow = bool(on)
        self._followed = None
        if self.follow:
            self.stage_camera = False
            self._framed = False

    def _follow_meshes(self) -> None:
        if self._followed is None or self._followed[0] == self.frame:
            return
        centre = self._meshes_centre()
        self.orbit.centre = self.orbit.centre + (centre - self._followed[1])
        self._followed = (self.frame, centre)

    def camera_record(self, width: int, height: int):
        """The camera the view draws through (the orbit, or the stage's as render)."""
        if self.stage_camera:
            return self.engine.sample(self.frame, width / height).camera
        if not self._framed:
            self.frame_view(width / height)
        if self.follow:
            self._follow_meshes()
        return self.orbit.record(width / height)

    def render(self, width: int, height: int, quality: Quality = FULL) -> ViewImage:
        """Draw the current frame: RGBA codes, as ``usdwrinkle render`` writes a PNG
        (with the stage's camera and FULL quality, the same codes)."""
        import time

        from ..render.request import FrameRequest

        started = time.perf_counter()
        w = max(1, int(round(width * quality.scale)))
        h = max(1, int(round(height * quality.scale)))
        camera = self.camera_record(w, h)
        self._apply_display()
        image = self.engine.render(self.frame, FrameRequest(
            w, h, quality.samples, shade_samples=quality.samples > 1, relief=self.relief,
            layout=self._layout, camera=camera))
        pixels = np.array(image.planes["RGBA"], copy=True)
        image.release()
        self._camera = (camera, w, h)
        self._posed.clear()
        self.last_frame = ViewImage(pixels, w, h, camera, quality, self.frame,
                                time.perf_counter() - started, dict(self.engine.last_timings))
        return self.last_frame

    def _ensure_posed(self) -> None:
        if not self.engine.is_posed(self.active):
            self.engine.compute_frame(self.frame)

    def posed_points(self, path: str) -> np.ndarray:
        """``path``'s posed points (world) at the last drawn frame (the brush outline, the
        q segments and picking read them); read from the engine once per frame."""
        if path not in self._posed:
            self._posed[path] = self.engine.posed_points(path)
        return self._posed[path]

    # -- picking --------------------------------------------------------------------
    def pick(self, x: float, y: float, width: int, height: int) -> Hit | None:
        """The nearest wrinkled-mesh point under pixel (x, y) of a ``width`` x ``height``
        view of the last drawn frame (the same camera), or None; the side of its mesh it
        meets is kept for ``facing``."""
        if self._camera is None:
            return None
        camera, w, h = self._camera
        origin, direction = pixel_ray(camera, x * w / width, y * h / height, w, h)
        best: Hit | None = None
        best_side = 1.0
        for path in self.engine.visible_paths():
            points = self.posed_points(path)
            triangles = self.engine.meshes[path].topology.triangles
            found = ray_triangles(origin, direction, points, triangles)
            if found is None or (best is not None and found[1] >= best.distance):
                continue
            tri, distance, bary = found
            rest = self.engine.meshes[path].rest_points[triangles[tri]].astype(np.float64)
            best = Hit(path, tri, bary, bary @ rest, distance)
            corners = points[triangles[tri]].astype(np.float64)
            normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
            best_side = 1.0 if normal @ direction <= 0.0 else -1.0  # the ray meets its front
        if best is not None and best.path not in self.meshes:
            return None  # an occluder that is not painted
        if best is not None:
            # the side of the mesh the eye sees there (Storm draws both sides of every
            # mesh): front-facing only paints, and "show q" shows, the points facing the
            # eye on that side
            self._sides[best.path] = best_side
        return best

    def facing(self, path: str, side: float | None = None) -> np.ndarray:
        """Per vertex of ``path``: whether its posed normal faces the eye on ``side``
        (1: the front, -1: the back; by default the side the last pick met on that mesh,
        the front before any). A curtain seen from behind shows its back: its back-facing
        points are the ones an artist paints (all 92 of the curtain sample's at its
        opening view, where before a stroke across it touched none)."""
        camera = self._camera[0]
        points = self.posed_points(path)
        normals = vertex_normals(points, self.engine.meshes[path].topology.triangles)
        if side is None:
            side = self._sides.get(path, 1.0)
        return side * np.einsum("ij,ij->i", normals, camera.position - points) > 0.0

    # -- strokes --------------------------------------------------------------------
    def begin_stroke(self, x: float, y: float, width: int, height: int,
                     pressure: float = 1.0, mode: str | None = None) -> bool:
        """Start a stroke at pixel (x, y); False where it misses every painted mesh.
        ``mode``: this stroke's brush mode instead of the brush's (the window's Shift
        smooths and Ctrl erases while held), the brush's other settings as they are."""
        hit = self.pick(x, y, width, height)
        if hit is None:
            return False
        self.active = hit.path
        mesh = self.mesh
        brush = self.brush if mode is None or mode == self.brush.mode else \
            replace(self.brush, mode=mode)
        self._stroke = Stroke(mesh, brush)
        self._stroke_before = (mesh.q.copy(), mesh.width.copy())
        self._stroke_facing = self.facing(hit.path)
        self._stroke_sample = (x, y, np.asarray(hit.rest_point, np.float64), None)
        self._stroke.add(hit, self._stroke_facing, pressure)
        self._preview_mesh(mesh)
        return True

    def drag(self, x: float, y: float, width: int, height: int,
             pressure: float = 1.0) -> int:
        """The drag moved to pixel (x, y); returns the stamps placed."""
        if self._stroke is None:
            return 0
        hit = self.pick(x, y, width, height)
        if hit is None or hit.path != self.active:
            return 0
        placed = self._stroke.add(hit, self._stroke_facing, pressure,
                                  min_step=self._screen_step(x, y, hit))
        if placed:
            self._preview_mesh(self.mesh)
        return placed

    def _screen_step(self, x: float, y: float, hit: Hit) -> float | None:
        """The rest-space length of SCREEN_SPACING pixels where the drag is, measured
        between its samples (rest travel over pixel travel; the last measure where the
        cursor has not moved): stamps are never farther apart than that on screen."""
        last_x, last_y, last_rest, per_pixel = self._stroke_sample
        rest = np.asarray(hit.rest_point, np.float64)
        pixels = float(np.hypot(x - last_x, y - last_y))
        if pixels >= 1.0:
            per_pixel = float(np.linalg.norm(rest - last_rest)) / pixels
            self._stroke_sample = (x, y, rest, per_pixel)
        return None if per_pixel is None else SCREEN_SPACING * per_pixel

    @property
    def stroking(self) -> bool:
        return self._stroke is not None

    def end_stroke(self) -> Edit | None:
        """End the stroke: author it (one undo step); None if it changed nothing."""
        stroke, before = self._stroke, self._stroke_before
        self._stroke = self._stroke_before = None
        if stroke is None:
            return None
        self.stamp_centres = list(stroke.centres)
        self.last_touched = np.array(sorted(stroke.touched), np.int64)
        mesh = self.mesh
        if np.array_equal(before[0], mesh.q) and np.array_equal(before[1], mesh.width):
            return None
        return self._record(Edit(mesh.path, "paint", before,
                                 (mesh.q.copy(), mesh.width.copy())))

    def untouched(self) -> str | None:
        """Why the last stroke, which met a mesh, touched none of its points (None if it
        touched some, or placed no stamp): none lay within the brush's radius (and, with
        front-facing only, faced the eye on the side the brush met)."""
        if len(self.last_touched) or not self.stamp_centres:
            return None
        brush, mesh = self.brush, self.mesh
        return (f"the brush (radius {brush.radius:.3g}) reached no point of {mesh.path} "
                f"(about {mesh.mean_edge():.3g} apart): raise it with ]")

    def cancel_stroke(self) -> None:
        """Drop the stroke in progress (Esc): the values before it come back."""
        if self._stroke is None:
            return
        mesh = self.mesh
        mesh.q[:], mesh.width[:] = self._stroke_before
        self._stroke = self._stroke_before = None
        # the stroke was only previewed (never authored): the engine's tables go back to
        # the values before it, so the next frame shows what the layer holds
        self._preview_mesh(mesh)

    def flood(self) -> Edit | None:
        """The brush's mode over the whole active mesh (one undo step); comb floods
        along the last stroke's direction, else the view's horizontal axis."""
        mesh = self.mesh
        before = (mesh.q.copy(), mesh.width.copy())
        direction = None
        if self.brush.mode in DIRECTED:
            direction = self._last_direction()
        flood(mesh, self.brush, direction)
        if np.array_equal(before[0], mesh.q) and np.array_equal(before[1], mesh.width):
            return None
        return self._record(Edit(mesh.path, "paint", before,
                                 (mesh.q.copy(), mesh.width.copy())))

    def _last_direction(self) -> np.ndarray:
        if self._last_stroke_direction is not None:
            return self._last_stroke_direction
        if self.orbit is not None:
            return self.orbit.basis()[1]
        return np.array([1.0, 0.0, 0.0])

    def _preview_mesh(self, mesh: PaintMesh) -> None:
        if self._stroke is not None and self._stroke.direction is not None:
            self._last_stroke_direction = self._stroke.direction
        self.engine.preview_params(mesh.path, q=clamp_unit(mesh.q).astype(np.float32),
                                   width=mesh.width.copy())

    # -- live controls ------------------------------------------------------------------
    def control(self, name: str) -> float:
        """A live control's value on the active mesh (width: the median W), as the session
        holds it now: its own W, and the stage's authored value of the others (the
        engine's copy is stale until its next frame, so an undo reads the stage)."""
        if name == "width":
            return float(np.median(self.mesh.width))
        attribute = self.stage.GetPrimAtPath(self.active).GetAttribute(CONTROLS[name][0])
        if attribute and attribute.HasAuthoredValue():
            return float(attribute.Get())
        return float(getattr(self.engine.meshes[self.active].params, name))

    def set_control(self, name: str, value: float, live: bool = False) -> Edit | None:
        """Set a control of the active mesh: ``live`` while the slider moves (drawn at
        once, not authored), else authored (one undo step, from the value before the
        slider moved)."""
        if name not in CONTROLS:
            raise UsdWrinkleError(f"unknown control {name!r} (one of {', '.join(CONTROLS)})")
        _, low, high = CONTROLS[name]
        import numbers

        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise UsdWrinkleError(f"`{name}` must be a number, not {value!r}", self.active)
        value = float(value)
        if not np.isfinite(value) or value < low or (high is not None and value > high):
            raise UsdWrinkleError(f"{name} {value:g} must be in [{low:g}, "
                                  f"{'inf' if high is None else f'{high:g}'}]", self.active)
        mesh = self.mesh
        if self._live is None or self._live["name"] != name:
            self._live = {"name": name, "before": self._control_value(name)}
        if name == "width":
            mesh.width[:] = value
            self.engine.preview_params(mesh.path, width=mesh.width.copy())
        else:
            self.engine.preview_params(mesh.path, **{name: value})
        if live:
            return None
        before = self._live["before"]
        self._live = None
        after = self._control_value(name) if name == "width" else value
        return self._record(Edit(mesh.path, name, before, after))

    def _control_value(self, name: str):
        if name == "width":
            return self.mesh.width.copy()
        return self.control(name)

    def set_cloth(self, preset: str) -> Edit | None:
        """Author ``wrinkle:cloth`` (the width follows it where none is authored)."""
        if preset not in CLOTH_PRESETS:
            raise UsdWrinkleError(f"unknown cloth {preset!r} (one of {', '.join(CLOTH_PRESETS)})")
        prim = self.stage.GetPrimAtPath(self.active)
        attr = prim.GetAttribute(schema.CLOTH)
        before = attr.Get() if attr and attr.HasAuthoredValue() else None
        return self._record(Edit(self.active, "cloth", before, preset))

    # -- undo -----------------------------------------------------------------------
    def _record(self, edit: Edit) -> Edit:
        snapshot = _snapshot(self.layer, edit.path)
        try:
            self._author(edit.path, edit.name, edit.after)
        except Exception:
            self._roll_back(edit, snapshot)
            raise
        if len(self.undo_stack) < self._saved_at:
            self._saved_at = -1  # the saved state is gone from the stack
        self.undo_stack.append(edit)
        self.redo_stack.clear()
        return edit

    def _roll_back(self, edit: Edit, snapshot) -> None:
        """An edit that authoring refused leaves nothing behind: the layer's specs of the
        prim as they were, and the values before it on the mesh and in the view (never
        half an edit on the layer, nor a session that refuses every later stroke)."""
        _restore(self.layer, edit.path, snapshot)
        mesh = self.meshes.get(edit.path)
        if mesh is not None:
            if edit.name == "paint":
                mesh.q[:], mesh.width[:] = edit.before
            elif edit.name == "width":
                mesh.width[:] = edit.before
            self._preview_mesh(mesh)
        self._live = None

    def undo(self) -> Edit | None:
        if not self.undo_stack:
            return None
        edit = self.undo_stack.pop()
        self._author(edit.path, edit.name, edit.before)
        self.redo_stack.append(edit)
        return edit

    def redo(self) -> Edit | None:
        if not self.redo_stack:
            return None
        edit = self.redo_stack.pop()
        self._author(edit.path, edit.name, edit.after)
        self.undo_stack.append(edit)
        return edit

    def _author(self, path: str, name: str, value) -> None:
        """Author one step's values on the edit layer through the WrinkleAPI (checked
        as ``check`` checks them); the engine sees the edit at the next frame."""
        from ..authoring import WrinkleAPI

        prim = self.stage.GetPrimAtPath(path)
        api = WrinkleAPI(prim) if schema.has_wrinkle_api(prim) else WrinkleAPI.Apply(prim)
        mesh = self.meshes[path]
        with Sdf.ChangeBlock():
            if name == "paint":
                q, width = value
                mesh.q[:], mesh.width[:] = q, width
                api.set_q(q)
                self._author_width(api, width)
            elif name == "width":
                mesh.width[:] = value
                self._author_width(api, value)
            elif name == "cloth":
                attr = prim.GetAttribute(schema.CLOTH)
                if value is None:
                    if attr:
                        prim.RemoveProperty(schema.CLOTH)
                else:
                    api.CreateClothAttr(value)
            elif name == "amplitude_scale":
                api.CreateAmplitudeScaleAttr(float(value))
            elif name == "slack":
                api.CreateSlackAttr(float(value))
            elif name == "irregularity":
                api.CreateIrregularityAttr(float(value))
        if name == "cloth":
            self.reload()  # the width follows the preset
        self._live = None

    def _author_width(self, api, width: np.ndarray) -> None:
        """W as authored: one value when it is the same everywhere, else per point; not
        authored where it equals what the stage gives already (a cloth preset, say) and
        the edit layer holds no W yet. Once it holds one, every step writes its W: the
        engine's copy of the stage is stale until its next frame, so an undo right after
        a change must not be compared with it."""
        path = api.GetPath()
        held = self.layer.GetAttributeAtPath(path.AppendProperty(schema.WIDTH))
        current = self.engine.meshes[path.pathString].params.width
        if held is None and np.array_equal(np.asarray(current, np.float32), width):
            return
        values = width[:1] if np.all(width == width[0]) else width
        api.CreateWidthPrimvar(np.asarray(values, np.float32))

    # -- save -----------------------------------------------------------------------
    def save(self, path: str | None = None) -> str | None:
        """Write the edit layer atomically to ``path`` (default: the session's save path);
        returns where it went (None: an in-memory layer, only marked saved).

        Save As never replaces a file the stage reads (the stage, its sublayers, packages,
        references, textures; by real path and by inode, so no spelling gets through)
        other than the edit layer's own file, and rewrites the layer's relative asset
        paths so that they name the same files from the new folder."""
        from ..outputs.atomic import atomic_path
        from ..outputs.layers import check_layer_path, export_layer, reanchored_copy

        target = path or self.save_path
        if target is None:
            if not self.in_memory:
                raise UsdWrinkleError("this session has no layer file to save to (a "
                                      "package is not edited in place): save as a new layer")
            self._saved_at = len(self.undo_stack)
            return None
        if not isinstance(target, (str, os.PathLike)):
            raise UsdWrinkleError(f"`path` must be a file path, not {type(target).__name__}")
        target = os.fspath(target)
        check_layer_path(target)
        if not self._is_own_file(target) and self._inputs().protects(target):
            raise UsdWrinkleError(f"cannot save the painted layer as '{target}': it is a "
                                  "file the stage reads (the stage, one of its layers, a "
                                  "package or a texture); choose a new layer path")
        folder = os.path.dirname(os.path.abspath(target))
        if not os.path.isdir(folder):
            raise UsdWrinkleError(f"cannot save the painted layer as '{target}': the folder "
                                  f"'{folder}' does not exist")
        layer = self.layer
        if layer.anonymous or not self._is_own_file(target):
            layer = reanchored_copy(self.layer, target, relative=self.layer.anonymous)
        with atomic_path(target) as tmp:
            export_layer(layer, tmp, target)
        self.save_path = target
        self._saved_at = len(self.undo_stack)
        return target

    def recovery_path(self) -> str:
        """Where write_recovery puts the unsaved strokes: beside the layer's file (or the
        stage's), named ``NAME.recovery.usda``."""
        base = self.save_path or (None if self.layer.anonymous else self.layer.realPath) \
            or self.stage.GetRootLayer().realPath or os.path.join(os.getcwd(), "paint")
        base = base.split("[")[0]
        stem = os.path.splitext(base)[0]
        return f"{stem}.recovery.usda"

    def write_recovery(self) -> str:
        """Write the edit layer, strokes and all, to recovery_path(), whatever the state of
        the session (a stop that cannot wait for an answer); the session stays dirty and
        its save path unchanged. Returns the path."""
        from ..outputs.atomic import atomic_path
        from ..outputs.layers import export_layer, reanchored_copy

        target = self.recovery_path()
        if self._inputs().protects(target):
            target = os.path.join(os.path.dirname(target), "usdwrinkle-paint.recovery.usda")
        layer = reanchored_copy(self.layer, target, relative=self.layer.anonymous)
        with atomic_path(target) as tmp:
            export_layer(layer, tmp, target)
        return target

    def _is_own_file(self, target: str) -> bool:
        """Whether ``target`` is the file the edit layer was read from (the session's save
        path, or the root layer edited in place), by any spelling."""
        own = [p for p in (self.save_path, None if self.layer.anonymous
                           else self.layer.realPath) if p and "[" not in p]
        for item in own:
            try:
                if os.path.realpath(item) == os.path.realpath(target) or \
                        os.path.samefile(item, target):
                    return True
            except OSError:
                continue
        return False

    def _inputs(self):
        """Every file the painted stage reads (scene/stage.stage_inputs), also through the
        sublayers of a new, anonymous paint layer."""
        from ..scene.inputs import StageInputs, scan_inputs
        from ..scene.stage import stage_inputs

        inputs = stage_inputs(self.stage) if not self.stage.GetRootLayer().anonymous \
            else StageInputs()
        for layer in self.stage.GetUsedLayers():
            if layer.anonymous or not layer.realPath:
                continue
            disk = layer.realPath.split("[")[0]
            inputs.add_file(disk)
            if layer is not self.layer and not disk.lower().endswith(".usdz"):
                scanned = scan_inputs(disk)
                inputs.files |= scanned.files
                inputs.inodes |= scanned.inodes
                inputs.missing |= scanned.missing
        return inputs

    def release(self) -> None:
        self.engine.release()


def _snapshot(layer: Sdf.Layer, path: str):
    """What ``layer`` holds at prim ``path`` (and which of its ancestors it has), so that
    a refused edit can be undone on the layer exactly: (existing prefixes, a copy)."""
    prim = Sdf.Path(path)
    existed = [p for p in prim.GetPrefixes() if layer.GetPrimAtPath(p)]
    copy = None
    if layer.GetPrimAtPath(prim):
        copy = Sdf.Layer.CreateAnonymous(".usda")
        Sdf.CreatePrimInLayer(copy, prim)
        Sdf.CopySpec(layer, prim, copy, prim)
    return existed, copy


def _restore(layer: Sdf.Layer, path: str, snapshot) -> None:
    existed, copy = snapshot
    prim = Sdf.Path(path)
    if copy is not None:
        Sdf.CopySpec(copy, prim, layer, prim)
        return
    created = [p for p in prim.GetPrefixes() if p not in existed and layer.GetPrimAtPath(p)]
    if created:
        edit = Sdf.BatchNamespaceEdit()
        edit.Add(Sdf.NamespaceEdit.Remove(created[0]))  # the topmost new one, and below
        layer.Apply(edit)


def session_for(stage_path: str, output: str | None = None, **kwargs) -> PaintSession:
    """The session of ``usdwrinkle paint STAGE [-o LAYER]`` (open_paint_stage)."""
    stage, layer, save = open_paint_stage(stage_path, output)
    return PaintSession(stage, layer, save, **kwargs)


def with_brush(session: PaintSession, **changes) -> BrushSettings:
    """Change the session's brush (checked); returns it."""
    session.brush = replace(session.brush, **changes)
    return session.brush


def check_paintable(stage, prim: str | None, all_meshes: bool,
                    camera: str | None = None) -> None:
    """Refuse, before a window opens, a stage with nothing to paint, a ``prim`` that is
    not a mesh of it (or one without WrinkleAPI, unless ``all_meshes``), and a ``camera``
    the stage does not have (the session would say so inside an empty window)."""
    from pxr import Usd, UsdGeom

    from ..scene.camera import find_camera

    meshes = [p for p in stage.Traverse(Usd.TraverseInstanceProxies()) if p.IsA(UsdGeom.Mesh)]
    if prim is not None and str(prim) not in {str(p.GetPath()) for p in meshes}:
        raise UsdWrinkleError(f"`prim` {prim} is not a Mesh of the stage")
    if not all_meshes and not any(schema.has_wrinkle_api(p) for p in meshes):
        if paths := schema.unapplied_controls(stage):
            raise UsdWrinkleError(schema.unapplied_message(paths))
        raise UsdWrinkleError("no mesh has WrinkleAPI applied, so there is nothing to paint "
                              "(pass `all_meshes` to paint every mesh, or apply WrinkleAPI "
                              "with usdwrinkle apply)")
    if prim is not None and not all_meshes and \
            not schema.has_wrinkle_api(stage.GetPrimAtPath(str(prim))):
        raise UsdWrinkleError(f"`prim` {prim} has no WrinkleAPI applied (apply it with "
                              "usdwrinkle apply, or pass `all_meshes`)")
    if camera is not None:
        find_camera(stage, camera)


def check_frame(frame, stage=None) -> float | None:
    """The frame a session opens on: None or a finite time code (a UsdWrinkleError naming
    `frame` otherwise); a frame outside the stage's range is said, as render says it."""
    import numbers

    from ..scene.stage import outside_range_note
    from .frames import check_time_code

    if frame is None:
        return None
    if isinstance(frame, bool) or not isinstance(frame, numbers.Real):
        raise UsdWrinkleError(f"`frame`={frame!r} must be a number")
    value = check_time_code(float(frame), "`frame`")
    if stage is not None and (note := outside_range_note(stage, [value])):
        import logging

        logging.getLogger(__name__).warning(note.split(": they show")[0]
                                            + ": the view shows the animation held at its "
                                              "ends")
    return value
