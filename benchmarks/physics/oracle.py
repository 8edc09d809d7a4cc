"""One shot against the cloth oracle: bake usdwrinkle on the coarse mesh and measure it
against the simulation (measure.py) at the same material points."""
from __future__ import annotations

import os
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import measure
from .shots import Shot
from .simulate import simulate
from .stage import MESH, levels, read_fine, write_stage


@dataclass
class Simulated:
    shot: Shot
    points: np.ndarray           # (frames, n, 3)
    h: np.ndarray                # (frames, n) fold height
    seconds: float
    wavelength: float = 0.0      # m, material, over the measured frames


@dataclass
class Baked:
    label: str
    h: np.ndarray
    width: float | None
    metrics: dict = field(default_factory=dict)
    waves: dict = field(default_factory=dict)   # the coarse mesh's baked waves
    points: np.ndarray | None = None            # (frames, n, 3) the displaced fine points
    flat: np.ndarray | None = None              # the same with no wrinkles
    normals: np.ndarray | None = None           # the undisplaced surface's normals


def measured_frames(shot: Shot) -> list[int]:
    """0-based frames where the measurements are taken: the end of every phase."""
    return sorted({end - 1 for _, end in shot.phases.values()})


def moving_frames(shot: Shot) -> list[int]:
    """0-based frames over which the fields are compared: from the frame before the first
    phase starts to the last."""
    return list(range(min(start for start, _ in shot.phases.values()) - 1, shot.frames))


#: grid lines this close to an open border are left out of every statistic: there the
#: low-pass (a renormalised Gaussian) departs from the pinned rows it cannot see past
MARGIN = 0.02
#: m, the sleeve this close to its middle is "the elbow"
ELBOW_ZONE = 0.15


def zones(shot: Shot) -> dict:
    """Masks on the grid: ``all`` (the cloth less the MARGIN), ``held`` (within EDGE of a
    pinned point), ``focus`` (where direction is compared: the elbow on the sleeve)."""
    m = shot.material
    inner = (m[:, 1] > m[:, 1].min() + MARGIN) & (m[:, 1] < m[:, 1].max() - MARGIN)
    if not shot.periodic:
        inner &= (m[:, 0] > m[:, 0].min() + MARGIN) & (m[:, 0] < m[:, 0].max() - MARGIN)
    out = {"all": inner, "held": inner & (shot.held_distance() < measure.EDGE),
           "focus": inner}
    if shot.name.startswith("sleeve"):
        along = m[:, 1] - m[:, 1].max() / 2
        out["elbow"] = inner & (np.abs(along) < ELBOW_ZONE)
        out["focus"] = out["elbow"]
    return out


def simulated(shot: Shot, cache: Path, preset: str = "Cotton") -> Simulated:
    points, seconds = simulate(shot, cache, preset)
    sim = Simulated(shot, points, measure.sim_height(shot, points), seconds)
    frames = measured_frames(shot)
    sim.wavelength = float(np.mean([measure.wavelength(shot, sim.h[f]) for f in frames]))
    return sim


def bake(shot: Shot, sim: Simulated, label: str, width: float | None = None,
         attributes: dict | None = None, held: bool = True) -> Baked:
    """Bake the coarse shot with --geometry (and once with wrinkle:amplitudeScale 0 for
    the undisplaced surface) and read back the fold height on the grid. ``held``: the
    simulation's pinned points marked wrinkle:held (stage.write_stage)."""
    from usdwrinkle import api
    from usdwrinkle.process.log import collect

    frames = f"0:{shot.frames}"
    with tempfile.TemporaryDirectory(prefix="usdwrinkle-physics-") as scratch:
        fields = {}
        for name, scale in (("wrinkled", None), ("flat", 0.0)):
            stage = os.path.join(scratch, f"{name}.usda")
            layer = os.path.join(scratch, f"{name}_geometry.usdc")
            write_stage(stage, shot, sim.points, width=width, amplitude_scale=scale,
                        held=held, attributes=attributes)
            with collect() as messages:  # frame 0 (the rest pose) lies before the shot
                api.bake(stage, layer, frames=frames, geometry=True, levels=levels(shot))
            for message in messages:
                if "lie outside the stage's time range" not in message:
                    print(f"usdwrinkle: warning: {message}", file=sys.stderr)
            fields[name] = read_fine(layer, shot, shot.frames)
            if name == "wrinkled":
                waves = read_waves(layer, shot.frames)
    (points, _), (flat, normals) = fields["wrinkled"], fields["flat"]
    baked = Baked(label, measure.our_height(shot, points, flat, normals), width)
    baked.waves = waves
    baked.points, baked.flat, baked.normals = points, flat, normals
    return baked


def on_coarser_grid(baked: Baked, fine: Shot, shot: Shot) -> Baked:
    """A bake on ``fine``'s grid measured on ``shot``'s, the same shot at twice the spacing
    (its points are every other grid line of ``fine``'s): the fold height band-passed on
    that grid, as the simulation's is."""
    grid = np.arange(fine.rows * fine.cols).reshape(fine.rows, fine.cols)[::2, ::2].ravel()
    if len(grid) != shot.rows * shot.cols:
        raise ValueError(f"{fine.name}'s grid is not {shot.name}'s at half the spacing")
    points, flat, normals = (a[:, grid] for a in (baked.points, baked.flat, baked.normals))
    out = Baked(baked.label, measure.our_height(shot, points, flat, normals), baked.width)
    out.waves, out.points, out.flat, out.normals = baked.waves, points, flat, normals
    return out


def read_waves(layer_path: str, frames: int) -> dict:
    """The baked amplitude and wave vector of the coarse mesh, (frames, n) and
    (frames, n, 3), frame 1 first."""
    from pxr import Usd

    stage = Usd.Stage.Open(layer_path)
    prim = stage.GetPrimAtPath(MESH)
    out = {}
    for key, name in (("amplitude", "primvars:wrinkle:amplitude"),
                      ("k", "primvars:wrinkle:waveVector")):
        attr = prim.GetAttribute(name)
        out[key] = np.stack([np.asarray(attr.Get(f), np.float64)
                             for f in range(1, frames + 1)])
    return out


def motion_ratios(result: dict) -> dict:
    """compare's crest motions at the elbow, ours over the simulation's, by what the arm
    does ("bend", "held"; none on a shot without an elbow)."""
    return {key[7:-4]: result[key[:-4]] / max(result[key], 1e-12) for key in result
            if key.startswith("motion") and key.endswith(" sim")}


def compare(sim: Simulated, ours: Baked) -> dict:
    shot = sim.shot
    frames = measured_frames(shot)
    zone = zones(shot)
    moving = moving_frames(shot)
    a_sim = measure.amplitude_field(shot, sim.h[moving])
    a_our = measure.amplitude_field(shot, ours.h[moving])
    inner = zone["all"]
    out = {
        "correlation": measure.correlation(a_our[:, inner], a_sim[:, inner]),
        "correlation_free": measure.correlation(a_our[:, inner & ~zone["held"]],
                                                a_sim[:, inner & ~zone["held"]]),
        "amplitude_ratio": measure.rms(ours.h[frames], inner) / measure.rms(sim.h[frames],
                                                                            inner),
        "wavelength": float(np.mean([measure.wavelength(shot, ours.h[f]) for f in frames])),
        "direction_deg": float(np.mean([measure.angle_between(
            measure.structure_direction(shot, ours.h[f], zone["focus"]),
            measure.structure_direction(shot, sim.h[f], zone["focus"])) for f in frames])),
        "held_share": _share(ours.h[frames], zone["held"], inner),
        "held_share_sim": _share(sim.h[frames], zone["held"], inner),
    }
    out["wavelength_ratio"] = out["wavelength"] / sim.wavelength
    out["held_ratio"] = out["held_share"] / max(out["held_share_sim"], 1e-12)
    if "elbow" in zone:
        elbow = zone["elbow"]
        out["elbow_share"] = _share(ours.h[frames], elbow, inner)
        out["elbow_share_sim"] = _share(sim.h[frames], elbow, inner)
        for phase, (start, end) in shot.phases.items():
            span = range(start - 1, end - 2)
            out[f"motion {phase}"] = measure.crest_motion(shot, ours.h, elbow, span)
            out[f"motion {phase} sim"] = measure.crest_motion(shot, sim.h, elbow, span)
    return out


def _share(h: np.ndarray, mask: np.ndarray, inner: np.ndarray) -> float:
    energy = (h ** 2).sum(0)
    return float(energy[mask].sum() / max(energy[inner].sum(), 1e-300))


def per_phase(sim, ours) -> dict:
    """Each phase end: (ours / sim) of the material wavelength and of the RMS height."""
    shot = sim.shot
    inner = zones(shot)["all"]
    out = {}
    for name, (_, end) in shot.phases.items():
        f = end - 1
        out[name] = (measure.wavelength(shot, ours.h[f], inner)
                     / measure.wavelength(shot, sim.h[f], inner),
                     measure.rms(ours.h[f], inner) / max(measure.rms(sim.h[f], inner), 1e-12))
    return out
