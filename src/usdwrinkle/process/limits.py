"""Documented maxima: what usdwrinkle refuses instead of running for hours or filling memory.

Every limit is named in the error it causes, and in the README's troubleshooting table.
"""
from __future__ import annotations

#: frames in one run (--frames, or the stage's start..end)
MAX_FRAMES = 100_000
#: frames of phase history computed before the first requested frame
MAX_HISTORY_FRAMES = 100_000
#: |frame| (time code) that a FrameSpec, a stage's range or --history-start may name
MAX_TIME_CODE = 1e9
#: wrinkle:relaxIterations and --relax-iterations
MAX_RELAX_ITERATIONS = 10_000
#: points per mesh (the GPU tables index them with 24 bits)
MAX_POINTS = 1 << 24
#: neighbours (and incident triangles) a point's wave is fitted and relaxed from: a pass
#: loops over a ring serially, so beyond this a point reads this many of its ring, evenly
#: spaced (scene/topology.Topology.rings; a fan of 2 million triangles made one point's
#: ring the whole pass's time)
MAX_RING = 64
#: |profile sample|: profiles are shapes of order 1, scaled by the amplitude
MAX_PROFILE_VALUE = 1e3
#: wrinkle:amplitudeScale (a multiplier of the physical amplitude, normally about 1)
MAX_AMPLITUDE_SCALE = 1e3
#: |coordinate| in world space, and the largest wrinkle width: the GPU works in float32,
#: and squares of lengths must stay finite (3.4e38)
MAX_WORLD_COORDINATE = 1e15
#: the stage's metersPerUnit that cloth presets convert through: nanometres to gigametres
#: (1e-30 gave W = 8.5e28 scene units, beyond MAX_WORLD_COORDINATE)
METERS_PER_UNIT_RANGE = (1e-9, 1e9)
#: texture width or height (the GL 4.5 minimum of GL_MAX_TEXTURE_SIZE)
MAX_TEXTURE_SIZE = 16384
#: corners of one face: concave faces are ear-clipped (mapbox-earcut), whose time grows
#: faster than the corner count (0.7-1.0 s at 50,000 corners, 4-6 s at 100,000, 26 s at
#: 200,000 here), and no signal interrupts it
MAX_FACE_CORNERS = 50_000
#: relax iterations times the frames a run computes (preroll included): each limit above
#: is reasonable alone, their product is not (10^9 iterations). A relax iteration costs
#: 0.26 ms for the shirt and 0.65 ms for CesiumMan on llvmpipe, so this bound is about 9
#: and 22 minutes of relaxation; it admits 100,000 frames at 20 iterations
MAX_RELAX_WORK = 2_000_000
#: worker processes of a local Dask cluster per CPU core (each holds a GL context)
LOCAL_WORKERS_PER_CORE = 4
