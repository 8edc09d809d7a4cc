"""The passes, one module each, on one interface (base.py): the wave passes that run per
mesh and frame (skin, the posed normals, crush, relax: each registers itself) and the
draw. The maps and the displaced geometry evaluate the waves with passes of the same
interface (maps/raster.py, geometry/evaluate.py); the resolve and the mip chains are
render/resolve.py and render/mipmaps.py. This module holds the helpers every pass uses."""
from __future__ import annotations

import functools

import numpy as np


def set_uniforms(program, values: dict) -> None:
    """Set the uniforms a program actually uses (the compiler drops unused ones). A
    uniform keeps its value in the program, so one set to what it holds already is not
    set again: most of a frame's uniforms (the material's, the lights' of a still
    light rig) are the last frame's, and setting each cost Python and GL calls per frame
    (a tenth of the paper's shirt frame on a GPU node)."""
    kept = program.extra
    if kept is None:  # name -> (member or None, the value it holds)
        kept = program.extra = {}
    for name, value in values.items():
        entry = kept.get(name)
        if entry is None:
            try:
                entry = [program[name], None]
            except KeyError:
                entry = [None, None]
            kept[name] = entry
        member = entry[0]
        if member is None:
            continue
        if isinstance(value, np.ndarray):
            value = np.ascontiguousarray(value, dtype=value.dtype).tobytes()
            if value != entry[1]:
                member.write(value)
                entry[1] = value
        elif value != entry[1] or entry[1] is None:
            member.value = value
            entry[1] = value


def bind(units: dict, reads: dict | None = None, writes: dict | None = None,
         read_writes: dict | None = None, storage: dict | None = None) -> None:
    """Bind a pass's tables and buffers to the units it declares in render/bindings.py:
    tables it reads to texture units, tables it writes (or reads and writes in place) to
    image units, storage buffers to SSBO binding points."""
    for name, table in (reads or {}).items():
        table.use(units[name])
    for name, table in (writes or {}).items():
        table.bind_image(units[name])
    for name, table in (read_writes or {}).items():
        table.bind_image(units[name], read=True)
    for name, buffer in (storage or {}).items():
        buffer.bind_to_storage_buffer(units[name])


def irregular(res) -> bool:
    """Whether the mesh's blend runs the IRREGULAR variant (wrinkle:irregularity > 0)."""
    return res.record.params.irregularity > 0.0


def irregularity_uniforms(params) -> dict:
    """The IRREGULAR variant's uniforms (method/contract.py, IRREGULARITY_*): beta, the
    radians of the field added to the phases, and 1 / Lambda, Lambda IRREGULARITY_SCALE
    times the mesh's median width (painting W on a small region leaves the field where
    it is)."""
    from ...method.contract import IRREGULARITY_GAIN, IRREGULARITY_SCALE

    width = float(np.median(params.width)) if len(params.width) else 0.0
    return {"u_irregularity": float(IRREGULARITY_GAIN * params.irregularity),
            "u_irregularity_scale": 1.0 / (IRREGULARITY_SCALE * width) if width > 0 else 0.0}


def bind_wave(units: dict, res, program) -> None:
    """Bind what the wave blend reads (include/wave.glsl; the WAVE units of bindings.py)
    and set its uniforms on ``program``."""
    set_uniforms(program, {"u_profile_samples": float(len(res.record.params.height_profile)),
                           "u_systems": res.waves.systems})
    if irregular(res):
        set_uniforms(program, irregularity_uniforms(res.record.params))
        bind(units, reads={"WAVE_REST_POINTS": res.rest_points})
    res.profiles[0].use(location=units["WAVE_HEIGHT_PROFILE"])
    res.profiles[1].use(location=units["WAVE_GRADIENT_PROFILE"])
    bind(units, reads={"WAVE_POSED_POINTS": res.posed_points,
                       "WAVE_FIELDS": res.waves.current, "WAVE_PHASE": res.waves.phase,
                       "WAVE_TRIANGLES": res.triangles})


def groups(count: int, local_size: int) -> int:
    return max((count + local_size - 1) // local_size, 1)


def gl_matrix(row_vector_matrix: np.ndarray) -> np.ndarray:
    """A USD row-vector matrix as the float32 bytes GLSL reads as its transpose.

    GLSL is column-major, so uploading M row by row gives GLSL M^T, and then
    ``M^T * v`` in GLSL equals ``v * M`` in USD: no transpose is needed.
    """
    return np.ascontiguousarray(row_vector_matrix, dtype=np.float32)


def inverse(matrix: np.ndarray) -> np.ndarray:
    """np.linalg.inv of a square float64 matrix (LinAlgError where it is singular),
    remembered: a frame's camera, mesh and bind transforms are mostly the last frame's,
    and numpy's inv of a 4x4 costs about as much as the rest of a uniform's setting (the
    paper's shirt runs about 300 frames a second on a GPU node, its frame all Python)."""
    matrix = np.ascontiguousarray(matrix, np.float64)
    return _inverse(matrix.tobytes(), matrix.shape)


@functools.lru_cache(maxsize=64)
def _inverse(data: bytes, shape: tuple) -> np.ndarray:
    result = np.linalg.inv(np.frombuffer(data, np.float64).reshape(shape))
    result.flags.writeable = False  # shared by every caller of the same matrix
    return result


def normal_matrix(row_vector_matrix: np.ndarray) -> np.ndarray:
    """The column-vector 3x3 that takes normals through a row-vector matrix (the inverse
    transpose), as GLSL mat3 bytes."""
    m3 = np.asarray(row_vector_matrix, np.float64)[:3, :3]
    try:
        inverted = inverse(m3)
    except np.linalg.LinAlgError:
        inverted = np.eye(3)
    # row-vector normals: n' = n inverse(M3)^T, i.e. column-vector n' = inverse(M3) n;
    # GLSL reads the uploaded rows as columns, so upload the transpose
    return np.ascontiguousarray(inverted.T, np.float32)
