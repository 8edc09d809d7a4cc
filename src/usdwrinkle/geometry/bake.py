"""``bake --geometry``: a finer render mesh per wrinkled mesh that carries the wrinkles as
real displacement, with the coarse mesh as its proxy (geometry/subdivide.py for the
topology, geometry/evaluate.py on the GPU, geometry/layer.py for the layer).

The level count, unless ``--levels`` gives it, is the fewest for which (a) every fine
edge is at most W/S long in the rest pose (S samples per wavelength, default 6 for the
fold, times profile_sampling for a profile that turns faster: under
uniform compression the wave and the edges shrink together), and (b) fine edges advance
a wave's phase by at most 2 pi / S on 99% of the wrinkled triangles of every frame (the
posed waves, painted q included): the bake then surveys every frame's wave fields first
(frameloop.bake_layer). The last 1% are the pinches (the shirt's inner elbow) where the
relaxation has already given up on a coherent wave inside one coarse triangle; sampling
those at 6 per wavelength took the shirt from 4 to 6 levels (1.7 M points instead of
0.1 M, a 3.5 GB .usda) for no visible gain.
"""
from __future__ import annotations

import logging

import numpy as np

from ..method.contract import COARSENING_MAX
from ..method.profiles import fold_profile, turning_phase
from ..outputs.sink import BakeScene
from ..process.errors import UsdWrinkleError
from ..process.memory import require_memory
from .evaluate import GeometryEvaluator
from .layer import FineMeshWriter
from .options import PROFILE_SAMPLING_MAX, SAMPLED_ROUNDING, GeometryOptions
from .subdivide import (
    AUTO_FINE_POINTS,
    MAX_LEVELS,
    check_size,
    fine_point_count,
    levels_for,
    subdivide,
)

_log = logging.getLogger(__name__)

#: bytes a fine point costs per frame while the layer is built (points, normals, the
#: read-back copies)
BYTES_PER_POINT_FRAME = 2 * 12 + 2 * 16
#: the share of wrinkled triangles (over all frames) whose phase advance sets the levels
SURVEY_PERCENTILE = 99.0


def profile_sampling(height: np.ndarray) -> float:
    """How many times the samples per wavelength a mesh's height profile asks for: the
    fold's turning phase (at options.SAMPLED_ROUNDING) over the profile's, between 1 and
    options.PROFILE_SAMPLING_MAX (1 for the default fold and for the cosine)."""
    own = turning_phase(height)
    if not own > 0:  # it turns within a sample (a zigzag at the table's Nyquist rate)
        return PROFILE_SAMPLING_MAX
    reference = turning_phase(fold_profile(SAMPLED_ROUNDING))
    return float(np.clip(reference / own, 1.0, PROFILE_SAMPLING_MAX))


def check_geometry_options(options: GeometryOptions) -> None:
    if options.levels is not None and not 0 <= options.levels <= MAX_LEVELS:
        raise UsdWrinkleError(f"`levels` must be in 0..{MAX_LEVELS} (got {options.levels})")
    if not 1.0 <= options.samples_per_wavelength <= 64.0:
        raise UsdWrinkleError("`samples_per_wavelength` must be in 1..64 "
                              f"(got {options.samples_per_wavelength:g})")


def rest_phase_step(record) -> float:
    """The phase 2 pi |e| / w along the longest rest edge e, w = W cap / COARSENING_MAX
    (the smaller of its two ends'; cap the point's coarsening cap, folds.coarsening_cap):
    rule (a) of the level count. On flat cloth w = W, whose folds coarsen up to 1.5 W, so
    that S samples of W are 1.5 S of the widest fold; on curved cloth (cap 1) the folds
    keep W, and w = W / 1.5 samples them as finely (6 samples of a fold keep only
    sinc(pi / 6)^2 of its extra length: the referee's uncoarsened sleeves drew 0.92-0.94
    of their rest area at 6 samples, 0.95-0.98 at 9; docs/physics.md)."""
    triangles = record.topology.triangles
    if len(triangles) == 0:
        return 0.0
    rest = record.rest_points[triangles]
    lengths = np.linalg.norm(rest[:, [1, 2, 0]] - rest, axis=2)        # edge c: c -> c + 1
    cap = COARSENING_MAX if record.params.coarsening is None else record.params.coarsening
    width = (np.asarray(record.params.width, np.float64)
             * np.asarray(cap, np.float64) / COARSENING_MAX)[triangles]
    ends = np.minimum(width, width[:, [1, 2, 0]])
    return float(2 * np.pi * np.max(lengths / np.maximum(ends, 1e-30)))


def phase_advance(points: np.ndarray, triangles: np.ndarray, wave_vector: np.ndarray,
                  amplitude: np.ndarray) -> np.ndarray:
    """Per triangle, the largest |e . k| over its edges e and its wrinkled corners' wave
    vectors k: the phase (radians) a wave advances along one coarse edge (0: no wave)."""
    if len(triangles) == 0:
        return np.zeros(0, np.float32)
    corners = points[triangles]                                   # (m, 3, 3)
    edges = corners[:, [1, 2, 0]] - corners                       # edge c: corner c -> c + 1
    k = wave_vector[triangles]
    advance = np.abs(np.einsum("mei,mci->mec", edges, k))        # (m, edge, corner)
    wrinkled = (amplitude[triangles] > 0)[:, None, :]
    advance = np.where(wrinkled & np.isfinite(advance), advance, 0.0)
    return advance.max(axis=(1, 2)).astype(np.float32)


class GeometryBake:
    """The bake sink of the displaced render meshes (outputs/sink.py): plans the fine
    meshes of the scene's wrinkled meshes (after :meth:`survey` when it
    :attr:`needs_survey`), defines them at :meth:`begin`, evaluates and writes them per
    frame."""

    def __init__(self, scene: BakeScene, options: GeometryOptions):
        self.scene = scene
        self.meshes = scene.meshes
        self.options = options
        self.frames = list(scene.frames)
        #: per mesh, the per-triangle phase advances of the surveyed frames
        self.advances: dict[str, list[np.ndarray]] = {path: [] for path in scene.meshes}
        self.writers: dict[str, FineMeshWriter] = {}
        self.levels: dict[str, int] = {}
        self.fine_points: dict[str, int] = {}
        self._evaluator: GeometryEvaluator | None = None

    @property
    def needs_survey(self) -> bool:
        """Without --levels, every frame's waves are looked at before the topology."""
        return self.options.levels is None and bool(self.meshes)

    def survey(self, fields_by_path: dict) -> None:
        for path, fields in fields_by_path.items():
            if path in self.advances:
                advance = phase_advance(fields.points, self.meshes[path].topology.triangles,
                                        fields.wave_vector, fields.drawn_amplitude)
                self.advances[path].append(advance[advance > 0])

    def phase_step(self, path: str) -> float:
        """The surveyed advance per coarse edge that the levels must resolve."""
        values = np.concatenate(self.advances[path]) if self.advances[path] else []
        return float(np.percentile(values, SURVEY_PERCENTILE)) if len(values) else 0.0

    def begin(self, layer) -> None:
        """Choose the levels, refuse meshes that would be too large, subdivide, and define
        the fine meshes in ``layer``."""
        counts = {}
        for path, record in self.meshes.items():
            levels = self.options.levels
            if levels is None:
                samples = self.options.samples_per_wavelength * profile_sampling(
                    record.params.height_profile)
                levels = self._fitting_levels(path, record, max(
                    levels_for(rest_phase_step(record), samples),
                    levels_for(self.phase_step(path), samples)))
            counts[path] = check_size(path, len(record.rest_points),
                                      record.topology.triangles, levels)
            self.levels[path] = levels
        require_memory(sum(counts.values()) * max(len(self.frames), 1) * BYTES_PER_POINT_FRAME,
                       f"building the layer, the wrinkled meshes of {len(self.frames)} "
                       "frame(s) need", "pass fewer `levels` or bake fewer `frames` per layer")
        for path, record in self.meshes.items():
            fine = subdivide(record.rest_points, record.topology.triangles, self.levels[path])
            self.fine_points[path] = len(fine.points)
            writer = FineMeshWriter(self.scene, path, fine)
            writer.define(layer)
            self.writers[path] = writer

    def _fitting_levels(self, path: str, record, wanted: int) -> int:
        """The automatic level count, lowered until the fine mesh fits AUTO_FINE_POINTS
        (with a warning: the waves it no longer resolves fade to the smooth surface, the
        band limit, rather than the bake being refused)."""
        levels = wanted
        triangles = record.topology.triangles
        while levels > 0 and fine_point_count(len(record.rest_points), triangles,
                                              levels) > AUTO_FINE_POINTS:
            levels -= 1
        if levels < wanted:
            _log.warning(f"{path}: {wanted} subdivision levels would resolve its waves but make "
                         f"{fine_point_count(len(record.rest_points), triangles, wanted):,} "
                         f"fine points (more than {AUTO_FINE_POINTS:,}); baking {levels} levels, "
                         "where waves shorter than 2 fine edges fade to the smooth surface "
                         "(band limit); a smaller wrinkle:width asks for this, `levels` sets "
                         "the count")
        return levels

    def add_frame(self, frame: float, fields: dict, resources: dict) -> None:
        """Evaluate and record a frame from each mesh's GPU tables (``resources``)."""
        if not self.writers:
            return
        if self._evaluator is None:
            self._evaluator = GeometryEvaluator(self.scene.ctx)
        for path, writer in self.writers.items():
            res = resources[path]
            result = self._evaluator.evaluate(res, writer.fine)
            if not (np.all(np.isfinite(result.points)) and np.all(np.isfinite(result.normals))):
                raise UsdWrinkleError("the displaced points are not finite (NaN or Inf)", path)
            writer.add_frame(frame, result.points, result.normals)

    def finish(self) -> dict:
        """The layer's record of the fine meshes (the frames are written as they come)."""
        return {"geometry": {
            "levels": ",".join(f"{p}={n}" for p, n in sorted(self.levels.items())),
            "finePoints": int(sum(self.fine_points.values())),
            "meshes": ",".join(str(w.path) for w in self.writers.values())}}

    def commit(self) -> None:
        """Nothing beside the layer to move into place."""

    def release(self) -> None:
        if self._evaluator is not None:
            self._evaluator.release()
            self._evaluator = None
