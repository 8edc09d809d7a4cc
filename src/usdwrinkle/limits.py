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
#: |profile sample|: profiles are shapes of order 1, scaled by the amplitude
MAX_PROFILE_VALUE = 1e3
#: wrinkle:amplitudeScale (a multiplier of the physical amplitude, normally about 1)
MAX_AMPLITUDE_SCALE = 1e3
#: |coordinate| in world space, and the largest wrinkle width: the GPU works in float32,
#: and squares of lengths must stay finite (3.4e38)
MAX_WORLD_COORDINATE = 1e15
#: texture width or height (the GL 4.5 minimum of GL_MAX_TEXTURE_SIZE)
MAX_TEXTURE_SIZE = 16384
