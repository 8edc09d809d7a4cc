"""Test helpers. The stage builders themselves live in usdwrinkle.authoring.builders,
shared with the sample generator and the benchmarks."""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
from pxr import Sdf, UsdGeom, Vt

from usdwrinkle.authoring.builders import point_cache_stage  # noqa: F401


def rotation_matrix(axis, angle) -> np.ndarray:
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
                     [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
                     [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]])


def read_until(stream, pattern, timeout: float) -> bytes:
    """Read a child's pipe (binary) until ``pattern`` (a bytes regex) matches what was
    read, and return it: tests signal a process on an event it reported, never after a
    guessed delay. Fails when the stream ends or ``timeout`` passes first."""
    import os
    import select
    import time

    data = b""
    deadline = time.monotonic() + timeout
    fd = stream.fileno()
    while not pattern.search(data):
        left = deadline - time.monotonic()
        assert left > 0, f"timed out waiting for {pattern.pattern!r}; got {data[-400:]!r}"
        ready, _, _ = select.select([fd], [], [], left)
        if ready:
            chunk = os.read(fd, 65536)
            assert chunk, f"the stream ended before {pattern.pattern!r}; got {data[-400:]!r}"
            data += chunk
    return data


# --- shared by several test modules (one place, no test module imports another) ------

#: the sample shirt's sleeve
SLEEVE = "/World/Arm/Sleeve"

EXR_CHANNELS = ("R", "G", "B", "A", "wrinkle.height", "wrinkle.amplitude", "N.X", "N.Y", "N.Z",
                "Z")


def read_exr(path):
    buf = oiio.ImageBuf(str(path))
    spec = buf.spec()
    pixels = buf.get_pixels(oiio.FLOAT).reshape(spec.height, spec.width, spec.nchannels)
    return {name: pixels[..., i] for i, name in enumerate(spec.channelnames)}


def edited_copy(layer: Path, out: Path, edit) -> Path:
    """A copy of the bake ``layer`` at ``out`` (its sublayers still found), changed by
    ``edit(copy)``."""
    source = Sdf.Layer.FindOrOpen(str(layer))
    copy = Sdf.Layer.CreateNew(str(out))
    copy.TransferContent(source)
    copy.subLayerPaths[:] = [str(layer.parent / p) for p in source.subLayerPaths]
    edit(copy)
    copy.Save()
    return out


def set_sample(name, frame, transform):
    """An edit for edited_copy: the sleeve's baked primvar ``name`` at ``frame``
    replaced by ``transform(value)``."""
    def edit(layer):
        path = Sdf.Path(f"{SLEEVE}.primvars:wrinkle:{name}")
        value = np.asarray(layer.QueryTimeSample(path, frame), np.float32)
        new = transform(value)
        array = Vt.FloatArray.FromNumpy(new) if new.ndim == 1 else Vt.Vec3fArray.FromNumpy(new)
        layer.SetTimeSample(path, frame, array)
    return edit


def scratch_frames_since(started: float) -> list[str]:
    """Frames encoded in memory (/dev/shm) since ``started`` and left behind."""
    return [p.name for p in Path("/dev/shm").glob(".usdwrinkle-frame.*")
            if p.stat().st_mtime >= started]


def baked(layer_path, prim_path, frame):
    """({primvar name: values} of a baked mesh at ``frame``, with its points; the stage)."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(layer_path))
    prim = stage.GetPrimAtPath(prim_path)
    primvars = UsdGeom.PrimvarsAPI(prim)
    out = {}
    for name in ("amplitude", "compression", "waveVector", "phase", "direction"):
        primvar = primvars.GetPrimvar(f"wrinkle:{name}")
        assert primvar.GetInterpolation() == UsdGeom.Tokens.vertex
        out[name] = np.asarray(primvar.Get(frame), np.float64)
    out["points"] = np.asarray(UsdGeom.Mesh(prim).GetPointsAttr().Get(frame), np.float64)
    return out, stage


def interior(points, margin):
    """The points more than ``margin`` inside the x-y bounding box."""
    lo, hi = points.min(0), points.max(0)
    return np.all((points[:, :2] > lo[:2] + margin) & (points[:, :2] < hi[:2] - margin), axis=1)


def gpu_fields(ctx, stage, frame=1.0, path="/Sheet"):
    """(the computed fields as arrays, the MeshRecord) of one mesh at ``frame``."""
    from usdwrinkle.engine import WrinkleEngine

    engine = WrinkleEngine(stage, ctx=ctx)
    try:
        engine.compute_frame(frame)
        return engine.read_fields(path).arrays(), engine.meshes[path]
    finally:
        engine.release()


def random_cloth(seed):
    """An icosphere squashed by a smooth random field, with random painted q."""
    import trimesh

    rng = np.random.default_rng(seed)
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    rest = np.asarray(sphere.vertices, np.float32)
    faces = np.asarray(sphere.faces, np.int32)
    bend = rng.normal(size=(3, 3)) * 0.25
    posed = rest @ (np.eye(3) + bend) + 0.15 * np.sin(3 * rest[:, [1, 2, 0]])
    q = np.zeros_like(rest)
    painted = rng.random(len(rest)) < 0.3
    q[painted] = rng.normal(size=(painted.sum(), 3))
    q[painted] *= (rng.random(painted.sum()) * 0.9 / np.linalg.norm(q[painted], axis=1))[:, None]
    return rest, posed.astype(np.float32), faces, q.astype(np.float32)


def random_cloth_fields(ctx, seed: int, relax_iterations: int, meters: float | None = None):
    """A random cloth's GPU fields at its posed frame and crush's numpy reference of it:
    (posed points, the GPU's fields, its MeshRecord, the reference's fields). ``meters``:
    the stage's metersPerUnit (None: unauthored, USD's 0.01)."""
    rest, posed, faces, q = random_cloth(seed)
    stage = point_cache_stage(rest, {1: posed}, np.full(len(faces), 3), faces.ravel(), q=q,
                              width=0.2, relax_iterations=relax_iterations)
    if meters is not None:
        UsdGeom.SetStageMetersPerUnit(stage, meters)
    from usdwrinkle.reference.crush import crush as crush_reference

    ours, record = gpu_fields(ctx, stage)
    ref = crush_reference(rest, posed, record.topology, q, record.params.width,
                          slack=record.params.slack, hold=record.params.hold,
                          coarsening=record.params.coarsening)
    return posed, ours, record, ref


def read_pixels(path) -> np.ndarray:
    """An image file's pixels as float (OpenImageIO), failing when it cannot be read."""
    pixels = oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT)
    assert pixels.size, f"cannot read {path}"
    return pixels


def rendered_frames(stages: dict, folder, frame: int = 24, width: int = 160) -> dict:
    """``usdwrinkle render`` of each stage ({name: path}) at ``frame``, ``width`` pixels
    wide, into ``folder``: {name: pixels} (to compare a direct render with one from a
    bake)."""
    from usdwrinkle.cli.main import main

    images = {}
    for name, path in stages.items():
        out = Path(folder) / f"{name}.exr"
        assert main(["render", str(path), str(out), "--frames", str(frame), "--width",
                     str(width), "--quiet"]) == 0
        images[name] = read_pixels(out)
    return images


#: material name -> (diffuse colour, the purpose it is bound for) (bind_purpose_looks)
PURPOSE_LOOKS = {"Look": ((1, 0, 0), "allPurpose"), "Final": ((0, 0, 1), "full"),
                 "Proxy": ((0, 1, 0), "preview")}


def bind_purpose_looks(stage, prim_path: str) -> None:
    """Bind ``prim_path`` to a UsdPreviewSurface material per purpose (PURPOSE_LOOKS, under
    /Looks): all purposes red, full blue, preview green, as a pipeline binds a light
    look for viewers and a final one for renderers."""
    from pxr import Gf, Sdf, UsdShade

    binding = UsdShade.MaterialBindingAPI.Apply(stage.GetPrimAtPath(prim_path))
    for name, (colour, purpose) in PURPOSE_LOOKS.items():
        material = UsdShade.Material.Define(stage, f"/Looks/{name}")
        surface = UsdShade.Shader.Define(stage, f"/Looks/{name}/Surface")
        surface.CreateIdAttr("UsdPreviewSurface")
        surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*colour))
        material.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
        binding.Bind(material, materialPurpose=getattr(UsdShade.Tokens, purpose))



def sheet_stage(path, nx: int = 41) -> str:
    """A flat, still, symmetric sheet (2 x 2, z up) with WrinkleAPI and W = 0.2, written
    to ``path`` (the paint window's mirror and width tests)."""
    from usdwrinkle.authoring.builders import grid_sheet

    points, counts, indices = grid_sheet(nx, nx, 2.0)
    stage = point_cache_stage(points, {1.0: points, 2.0: points}, counts, indices, width=0.2)
    stage.GetRootLayer().Export(str(path))
    return str(path)


def x_env(display: str) -> dict:
    return {**os.environ, "DISPLAY": display, "QT_QPA_PLATFORM": "xcb"}


#: what an X client says when the server refused its connection. Xvfb refuses one now and
#: then under load: 2 of 280 xdotool calls in a row to a live Xvfb failed so while a CI run
#: ran beside it (10 of 261 while other servers started and stopped). The clients below try
#: again; the code under test is not involved before it has a connection
X_REFUSED = ("Can't open display", "could not connect to display",
             "no X server answers there")  # the paint command's own check, asked 4 times


def xdotool(display: str, *args: str, timeout: float = 60, check: bool = True) -> str:
    for _ in range(5):
        done = subprocess.run(["xdotool", *args], env=x_env(display), capture_output=True,
                              text=True, timeout=timeout)
        if not any(text in done.stderr for text in X_REFUSED):
            break
    if check:
        done.check_returncode()
    return done.stdout


def wait_for_session(display: str, window: str, timeout: float = 120) -> None:
    """Wait until the paint window ``window`` has made its session (its title then names
    the layer it saves: "usdwrinkle paint - PATH"): before that, the view has no mesh to
    take a stroke."""
    import time

    deadline = time.monotonic() + timeout
    while " - " not in xdotool(display, "getwindowname", window):
        if time.monotonic() > deadline:
            raise AssertionError(f"the paint window made no session within {timeout:g} s")
        time.sleep(0.1)


def start_window(display: str, argv: list, log_path, name: str = "usdwrinkle paint",
                 timeout: float = 120):
    """Start a window's process (its output in ``log_path``) and find its window: (the
    process, its open log, the window id). A process that could not reach the X server
    (X_REFUSED in its log, before any of our code ran) is started again, twice at most;
    one that never shows its window is killed."""
    for attempt in range(3):
        log = open(log_path, "w")
        process = subprocess.Popen(argv, env=x_env(display), stdout=log,
                                   stderr=subprocess.STDOUT)
        try:
            return process, log, find_window(display, name, process.pid, timeout,
                                             alive=lambda p=process: p.poll() is None)
        except AssertionError:
            if process.poll() is None:
                process.kill()
            process.wait(10)
            log.close()
            text = open(log_path).read()
            if attempt < 2 and any(refused in text for refused in X_REFUSED):
                continue
            raise AssertionError(f"no window {name!r}: {text[-2000:]}") from None
    raise AssertionError("unreachable")


def find_window(display: str, name: str, pid: int | None = None,
                timeout: float = 120, alive=None) -> str:
    """The first visible window called ``name`` (of process ``pid``, by its _NET_WM_PID,
    where given), polled until it shows. Not ``xdotool search --sync``: a window that Qt
    destroys while xdotool walks the tree, or a connection the X server refuses
    (X_REFUSED), ends xdotool with exit 1; and a search by name alone may find another
    process's window (a test's window that outlived it). ``alive``: a callable, False
    once the window's process has ended."""
    import time

    args = ["search", "--all", "--onlyvisible", *(["--pid", str(pid)] if pid else []), "--name",
            name]
    deadline = time.monotonic() + timeout
    last = None
    while time.monotonic() < deadline and (alive is None or alive()):
        last = subprocess.run(["xdotool", *args], env=x_env(display), capture_output=True,
                              text=True, timeout=60)
        if last.returncode == 0 and last.stdout.split():
            return last.stdout.split()[0]
        time.sleep(0.2)
    raise AssertionError(f"no visible window {name!r} within {timeout:g} s "
                         f"(xdotool: {last.stderr.strip() if last else ''})")


def fold_law(ratio, width, geometric=None, slack=0.0, height=None, cap=None, crests=False):
    """(amplitude, |k|) of the fold law (usdwrinkle/method/folds.py, docs/method.md) on an
    analytic sheet: ``ratio`` the compression along the wave with the painted q,
    ``geometric`` the mesh's alone (default: ``ratio``), with no room limit; ``cap`` the
    coarsening cap (flat cloth's COARSENING_MAX by default); ``slack`` wrinkle:slack,
    whose excess sets the wave, while the drawn fold's slope takes the drawn folds' slack
    (contract.DRAWN_SLACK of it); ``crests``: instead the fold the relaxation weighs the
    phases by (the slope with the slack itself)."""
    from usdwrinkle.method.contract import DRAWN_SLACK
    from usdwrinkle.method.folds import (
        excess_length,
        material_wavelength,
        profile_slope,
        slope_table,
    )
    from usdwrinkle.method.profiles import default_profile

    geometric = ratio if geometric is None else geometric
    rho = excess_length(ratio, geometric, slack)
    drawn = rho if crests else excess_length(ratio, geometric, DRAWN_SLACK * slack)
    wavelength = material_wavelength(width, rho) if cap is None else \
        material_wavelength(width, rho, cap)
    k = 2 * np.pi / (np.maximum(geometric, 1e-30) * wavelength)
    table = slope_table(default_profile() if height is None else height)
    amplitude = np.where(drawn > 1.0, profile_slope(table, drawn) / k, 0.0)
    return amplitude, k


#: the analytic sheet of the maps tests: W, and the map size
MAPS_WIDTH = 0.3
MAPS_SIZE = 256


def maps_sheet_stage(tmp_path, ratio, rotation=None, st=None, frames=(1,),
                     name="sheet.usda", **kwargs):
    """The analytic sheet compressed by ``ratio`` along x, UVs (x, y) -> [0, 1]^2."""
    from pxr import UsdGeom

    from usdwrinkle.authoring.builders import grid_sheet

    rest, counts, indices = grid_sheet(31, 31, 2.0)
    posed = rest * np.array([ratio, 1, 1], np.float32)
    if rotation is not None:
        posed = posed @ rotation.T.astype(np.float32) + np.array([0.3, -2.0, 1.0], np.float32)
    stage = point_cache_stage(rest, {f: posed for f in frames}, counts, indices,
                              width=MAPS_WIDTH, **kwargs)
    if st is None:
        st = (rest[:, :2] + 1.0) / 2.0
    if st is not False:
        UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/Sheet")).CreatePrimvar(
            "st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex).Set(
            Vt.Vec2fArray.FromNumpy(np.asarray(st, np.float32)))
    path = tmp_path / name
    stage.GetRootLayer().Export(str(path))
    return path


def bake_maps(source, layer, *args, kinds="normal,height,amplitude", size=MAPS_SIZE):
    """bake --maps; in the mesh's own texture coordinates unless ``args`` choose a layout
    (these tests read the maps' texels at the asset's UVs)."""
    from usdwrinkle.cli.main import main

    layout = () if "--map-layout" in args else ("--map-layout", "asset")
    return main(["bake", str(source), str(layer), "--quiet", "--maps", kinds,
                 "--map-size", str(size), *layout, *args])


def gathered_cuff(ratio: float = 1.0, radius: float = 0.1, length: float = 0.3,
                  along: int = 11, around: int = 96):
    """(points, counts, indices, interior mask): a tube of ``radius`` about the y axis (a
    cuff) ``length`` long, ``along`` rings of ``around`` points, its radius scaled by
    ``ratio`` (gathered around itself: its circumference compressed to ``ratio``, its
    length kept); normals outward; the interior 5 cm in from both ends."""
    from usdwrinkle.authoring.builders import grid_faces

    y, t = np.meshgrid(np.linspace(0, length, along),
                       np.arange(around) * 2 * np.pi / around, indexing="ij")
    theta = t.ravel()
    scaled = radius * ratio
    points = np.stack([scaled * np.sin(theta), y.ravel(), scaled * np.cos(theta)], 1)
    counts, indices = grid_faces(along, around, wrap_cols=True)
    inner = (y.ravel() > 0.05) & (y.ravel() < length - 0.05)
    return points, counts, indices, inner
