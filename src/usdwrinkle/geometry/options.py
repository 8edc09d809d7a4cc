"""What ``bake --geometry`` and its options ask for (light: the CLI's help reads the
defaults without loading the bake)."""
from __future__ import annotations

from dataclasses import dataclass

#: fine vertices per wavelength the default levels aim for (for the fold; a profile that
#: turns faster gets more: PROFILE_SAMPLING_MAX)
DEFAULT_SAMPLES_PER_WAVELENGTH = 6.0
#: the fold's rounding (method/profiles.FOLD_ROUNDING was 0.9 until 2026-12-08; the
#: default fold, 0.97, gets 1.79x) that those samples were measured
#: on: a mesh whose height profile turns faster than it (profiles.turning_phase) gets as
#: many times more, at most PROFILE_SAMPLING_MAX times (the triangle's kink resolves at
#: no count). The relief against the displaced slanted sheet at 55 degrees (tests/
#: test_relief.py), the normals' 90th percentile of difference at 6 a wavelength and at
#: the profile's own count: fold 6.8 degrees; sharp (1.48x) 33.8 and 8.2 at 9; box
#: (2x) 34.5 and 8.6 at 12; the fold at K = 0.97 (1.79x) 12.9 and 1.5 at 12
#: (docs/physics.md, "The fold's rounding, probed")
SAMPLED_ROUNDING = 0.9
PROFILE_SAMPLING_MAX = 2.0


@dataclass(frozen=True)
class GeometryOptions:
    """What ``--geometry`` and its options ask for."""

    levels: int | None = None
    samples_per_wavelength: float = DEFAULT_SAMPLES_PER_WAVELENGTH
