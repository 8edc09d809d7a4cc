"""Baked wave fields: the per-vertex primvars that ``usdwrinkle bake`` writes, read back
as the input of a render.

A render that finds them for a wrinkled mesh draws them as they are, and runs neither
crush nor relax for that mesh: no preroll, and the same crests on every machine,
whatever its GL implementation computes (docs/method.md, "Rendering from a bake").

Which frames a bake covers
--------------------------
- Time-sampled fields cover exactly the frames that have a sample. A frame between the
  first and the last sample that has none is an error ("missing from the baked range"),
  and so is a frame outside that range: interpolating phases would move crests, and
  computing those frames instead would put a jump at the range's ends. Bake the frames,
  or render with ``--recompute``.
- Fields authored only at the default time (the bake of a static stage) cover every frame.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pxr import Usd

from ..process.errors import UsdWrinkleError
from ..process.timecode import format_frame
from ..usd import schema

#: baked primvar -> (field, components), the required ones, the second system's
BAKED_PRIMVARS = schema.BAKED_PRIMVARS
REQUIRED = schema.BAKED_REQUIRED
SECOND_SYSTEM = schema.BAKED_SECOND_REQUIRED


@dataclass(frozen=True)
class BakedFields:
    """One mesh's baked wave fields at one frame.

    Attributes
    ----------
    amplitude : (n,) float32
        h = s (W/4) sqrt(1 - r^2), scene units (the amplitude scale is baked in).
    wave_vector : (n, 3) float32
        k in the mesh's local space, posed.
    phase : (n,) float32
        relaxed phase, radians.
    direction : (n, 3) float32
        rest-space direction of strongest compression (zeros when not baked).
    compression : (n,) float32
        r (ones when not baked).
    amplitude2, wave_vector2, phase2 : the second wave system, or None (one system).
    direction2, compression2 : the second system's rest direction and compression, which
        the irregular blend reads (zeros and ones from a bake made before they were
        written).
    offset : (n,) float32 or None
        The deepened pleats' offset along the normal (method/deepen.py); None: a bake
        that has none (made before it was drawn), drawn without it.
    """

    amplitude: np.ndarray
    wave_vector: np.ndarray
    phase: np.ndarray
    direction: np.ndarray
    compression: np.ndarray
    amplitude2: np.ndarray | None = None
    wave_vector2: np.ndarray | None = None
    phase2: np.ndarray | None = None
    direction2: np.ndarray | None = None
    compression2: np.ndarray | None = None
    offset: np.ndarray | None = None


class BakedSource:
    """The baked fields of one mesh prim, read frame by frame.

    Parameters
    ----------
    prim : Usd.Prim
        A mesh whose required baked primvars all have authored values.
    num_points : int
        Every field must have one value per point.
    """

    def __init__(self, prim: Usd.Prim, num_points: int):
        self.path = str(prim.GetPath())
        self.num_points = num_points
        self.attrs = {name: prim.GetAttribute(name) for name in BAKED_PRIMVARS
                      if prim.GetAttribute(name).HasAuthoredValue()}
        required = self.attrs[REQUIRED[0]]
        self.times = np.asarray(required.GetTimeSamples(), np.float64)
        for name in REQUIRED[1:]:
            times = np.asarray(self.attrs[name].GetTimeSamples(), np.float64)
            if len(times) != len(self.times) or np.any(times != self.times):
                raise UsdWrinkleError(
                    f"baked fields disagree on their frames ({len(times)} samples, "
                    f"{REQUIRED[0]} has {len(self.times)})", self.path, name)
        self._sampled = set(self.times.tolist())
        second = [name for name in SECOND_SYSTEM if name in self.attrs]
        if second and len(second) < len(SECOND_SYSTEM):
            missing = next(name for name in SECOND_SYSTEM if name not in self.attrs)
            raise UsdWrinkleError("incomplete second wave system: this primvar is missing "
                                  "(re-bake, or pass `recompute`)", self.path, missing)

    @property
    def static(self) -> bool:
        """Authored at the default time only: covers every frame."""
        return len(self.times) == 0

    def range_text(self) -> str:
        if self.static:
            return "default time"
        return f"{format_frame(self.times[0])}..{format_frame(self.times[-1])}"

    def covers(self, frame: float | None) -> bool:
        return self.static or (frame is not None and float(frame) in self._sampled)

    def check_covers(self, frame: float | None) -> None:
        """Raise the one-line error for a frame the bake does not hold."""
        if self.covers(frame):
            return
        attribute = REQUIRED[0]
        if frame is None:
            raise UsdWrinkleError(
                f"the baked fields have time samples ({self.range_text()}) but the default "
                "time is rendered; give `frames`, or pass `recompute`", self.path, attribute)
        first, last = self.times[0], self.times[-1]
        if first <= frame <= last:
            what = f"frame missing from the baked range {self.range_text()}"
        else:
            what = f"frame outside the baked range {self.range_text()}"
        raise UsdWrinkleError(f"{what}; bake this frame, or pass `recompute`", self.path,
                              attribute, frame)

    def at(self, frame: float | None) -> BakedFields:
        """The fields at ``frame`` (None: the default time), checked: length and
        finiteness."""
        self.check_covers(frame)
        time = Usd.TimeCode.Default() if frame is None or self.static \
            else Usd.TimeCode(frame)
        where = frame
        n = self.num_points
        values = {}
        for name, (field, components) in BAKED_PRIMVARS.items():
            attr = self.attrs.get(name)
            if attr is None:
                continue
            value = attr.Get(time)
            try:
                array = np.asarray(value, np.float32)
            except (TypeError, ValueError):
                array = np.zeros(0, np.float32)
            if value is None or array.size != n * components or (
                    components == 3 and array.ndim != 2) or (
                    components == 1 and array.ndim != 1):
                count = 0 if value is None else len(value)
                raise UsdWrinkleError(
                    f"baked field has {count} values for {n} points (or the wrong type)",
                    self.path, name, where)
            if not np.all(np.isfinite(array)):
                raise UsdWrinkleError("baked field is not finite (NaN or Inf)", self.path,
                                      name, where)
            values[field] = array.reshape(n, components) if components == 3 else array
        values.setdefault("direction", np.zeros((n, 3), np.float32))
        values.setdefault("compression", np.ones(n, np.float32))
        if "amplitude2" in values:
            values.setdefault("direction2", np.zeros((n, 3), np.float32))
            values.setdefault("compression2", np.ones(n, np.float32))
        else:
            values.pop("direction2", None)
            values.pop("compression2", None)
        return BakedFields(**values)


def find_baked(prim: Usd.Prim, num_points: int) -> BakedSource | None:
    """The mesh's baked fields, or None when it has none.

    Some but not all of the required primvars is an incomplete bake: an error.
    """
    authored = [name for name in REQUIRED if prim.GetAttribute(name).HasAuthoredValue()]
    if not authored:
        return None
    if len(authored) < len(REQUIRED):
        missing = next(name for name in REQUIRED if name not in authored)
        raise UsdWrinkleError("incomplete baked wave fields: this primvar is missing "
                              "(re-bake, or pass `recompute`)", str(prim.GetPath()), missing)
    return BakedSource(prim, num_points)


def holds_bake(stage: Usd.Stage) -> bool:
    """True when a layer of the stage was written by ``usdwrinkle bake`` (its
    customLayerData has a "usdwrinkle" entry): rendering it is rendering a bake."""
    return any("usdwrinkle" in layer.customLayerData
               for layer in stage.GetLayerStack(includeSessionLayers=False))


def geometry_bake(stage: Usd.Stage):
    """(layer path, first frame, last frame) of a ``bake --geometry`` layer in the stage's
    layer stack, or None. Its displaced meshes carry the wrinkles in their points: a
    render draws them with --no-wrinkles, and holds the nearest baked frame outside
    first..last."""
    for layer in stage.GetLayerStack(includeSessionLayers=False):
        data = layer.customLayerData.get("usdwrinkle")
        if data and "geometry" in data:
            first = layer.startTimeCode if layer.HasStartTimeCode() else None
            last = layer.endTimeCode if layer.HasEndTimeCode() else None
            return layer.realPath or layer.identifier, first, last
    return None

