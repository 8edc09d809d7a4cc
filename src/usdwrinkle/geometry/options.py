"""What ``bake --geometry`` and its options ask for (light: the CLI's help reads the
defaults without loading the bake)."""
from __future__ import annotations

from dataclasses import dataclass

#: fine vertices per wavelength the default levels aim for
DEFAULT_SAMPLES_PER_WAVELENGTH = 6.0


@dataclass(frozen=True)
class GeometryOptions:
    """What ``--geometry`` and its options ask for."""

    levels: int | None = None
    samples_per_wavelength: float = DEFAULT_SAMPLES_PER_WAVELENGTH
