"""Peers: the same shot through ``usdwrinkle render`` and through usdview's Storm.

CesiumMan, framed closely by one camera, 960x540, frames 1-24, to PNG:

- usdwrinkle: the whole process (``usdwrinkle render ... --all-meshes``, wrinkles on:
  start-up, USD, the four passes, the resolve and the PNG encodes), timed from outside;
- Storm: driven as usdrecord drives it (UsdAppUtils.FrameRecorder, usdview's camera light),
  the frame loop only: the sum of its Record calls, each of which renders and writes one
  PNG (realclients/storm_client.py), without its process's start-up.

The two alternate, three rounds (--quick, a smoke test, skips them); medians. Storm runs
in a Python with Blender's bpy wheel (realclients/__init__.py); without one the row says
why it did not run.
The child processes keep Python's bytecode cache, as an installed package has it (this
workplace sets PYTHONDONTWRITEBYTECODE, which would add about 40 ms of compiling to each
usdwrinkle start).
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

WIDTH, HEIGHT, FRAMES = 960, 540, 24
CAMERA = "/PeerCamera"


def closely_framed(corpus: Path, folder: Path) -> Path:
    """A layer over CesiumMan.usdz with a camera that frames his walk closely."""
    import numpy as np
    from pxr import Gf, Sdf, Usd, UsdGeom

    import usdwrinkle  # noqa: F401  (the schema before USD builds its registry)
    from usdwrinkle.scene.stage import StageSceneDelegate

    package = (corpus / "usd-wg" / "CesiumMan.usdz").resolve()
    if not package.is_file():
        raise FileNotFoundError(f"the peer shot needs {package}")
    path = folder / "cesium_close.usda"
    layer = Sdf.Layer.CreateNew(str(path))
    layer.subLayerPaths.append(str(package))
    source = Sdf.Layer.FindOrOpen(str(package))
    for key in ("upAxis", "metersPerUnit", "startTimeCode", "endTimeCode"):
        if source.pseudoRoot.HasInfo(key):
            layer.pseudoRoot.SetInfo(key, source.pseudoRoot.GetInfo(key))
    layer.Save()
    stage = Usd.Stage.Open(layer)
    lo, hi = StageSceneDelegate(stage, all_meshes=True).bounds()
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise RuntimeError(f"no mesh to frame in {package}")
    centre, size = (lo + hi) / 2, hi - lo
    fov = 30.0
    distance = 0.55 * size[1] / np.tan(np.radians(fov / 2))  # his height, 10% margin
    camera = Gf.Camera()
    camera.SetPerspectiveFromAspectRatioAndFieldOfView(WIDTH / HEIGHT, fov,
                                                       Gf.Camera.FOVVertical)
    eye = centre + np.array([0.25, 0.15, 1.0]) * distance
    camera.transform = Gf.Matrix4d().SetLookAt(Gf.Vec3d(*eye), Gf.Vec3d(*centre),
                                               Gf.Vec3d(0, 1, 0)).GetInverse()
    camera.clippingRange = Gf.Range1f(0.05, 100.0)
    UsdGeom.Camera.Define(stage, CAMERA).SetFromCamera(camera, Usd.TimeCode.Default())
    layer.Save()
    return path


def _ours(stage: Path, out: Path, *extra: str) -> float:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "usdwrinkle", "render", str(stage),
                    str(out / "c.####.png"), "--frames", f"1:{FRAMES}", "--width", str(WIDTH),
                    "--height", str(HEIGHT), "--camera", CAMERA, "--all-meshes", "--quiet",
                    *extra], check=True, env=env, capture_output=True)
    return time.perf_counter() - started


def _storm(stage: Path, out: Path) -> float:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from realclients import SECONDS, storm

    jobs = [{"stage": str(stage), "camera": CAMERA, "frame": frame, "width": WIDTH,
             "out": str(out / f"s.{frame:04d}.png"), "camera_light": True}
            for frame in range(1, FRAMES + 1)]
    results = storm(jobs)
    failed = {path: why for path, why in results.items() if why != "ok"}
    if failed:
        raise RuntimeError(f"Storm failed: {next(iter(failed.values()))}")
    return sum(SECONDS[job["out"]] for job in jobs)


def storm_peer(quick: bool, corpus: Path) -> dict:
    """The peer row: fps of both, and usdwrinkle's lead (or why it did not run)."""
    if quick:  # a smoke test: Blender's start-up alone is most of a quick bench's minute
        return {"ran": False, "why": "quick mode (the full bench times Storm)"}
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from realclients import NoClient, bpy_python

    try:
        bpy_python()
    except NoClient as exc:
        return {"ran": False, "why": str(exc)}
    rounds = 3
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        stage = closely_framed(corpus, folder)
        _ours(stage, folder)  # warm the shader caches, as a node's second job is
        ours, once, theirs = [], [], []
        for index in range(rounds):
            round_folder = folder / str(index)
            (round_folder / "once").mkdir(parents=True)
            ours.append(_ours(stage, round_folder))
            # every pixel shaded once: what shading the samples of wrinkled pixels costs
            once.append(_ours(stage, round_folder / "once", "--no-shade-samples"))
            theirs.append(_storm(stage, round_folder))
    ours_s, once_s = statistics.median(ours), statistics.median(once)
    storm_s = statistics.median(theirs)
    return {"ran": True, "shot": f"CesiumMan, {WIDTH}x{HEIGHT}, {FRAMES} frames, PNG",
            "rounds": rounds, "ours_s": ours, "once_s": once, "storm_s": theirs,
            "ours_fps": FRAMES / ours_s, "once_fps": FRAMES / once_s,
            "storm_fps": FRAMES / storm_s, "lead": storm_s / ours_s,
            "lead_once": storm_s / once_s}


def markdown(result: dict) -> list[str]:
    peers = result.get("peers")
    if peers is None:
        return []
    lines = ["", "## Against usdview's Storm", ""]
    if not peers["ran"]:
        return lines + [f"Not run: {peers['why']}."]
    rounds = ", ".join(f"{o:.2f} s / {s:.2f} s" for o, s in zip(peers["ours_s"],
                                                              peers["storm_s"], strict=True))
    once = "once_s" in peers   # runs kept from before the row had it lack it
    return lines + [
        f"{peers['shot']}, one camera framing his walk closely. usdwrinkle: the whole "
        "`usdwrinkle render ... --all-meshes` process with wrinkles (start-up, USD, the four "
        "passes, the resolve, the PNG encodes), timed from outside. Storm: driven as "
        "usdrecord drives it (UsdAppUtils.FrameRecorder with usdview's camera light), its "
        "frame loop only (the Record calls, each rendering and writing one PNG), without "
        "its process's start-up. They alternate, "
        f"{peers['rounds']} round(s), medians (`benchmarks/peers.py`).", "",
        "| | seconds for the shot | fps |", "|---|---|---|",
        f"| usdwrinkle, with wrinkles, whole process | {min(peers['ours_s']):.2f}-"
        f"{max(peers['ours_s']):.2f} | {peers['ours_fps']:.1f} |",
        *([f"| the same, `--no-shade-samples` | {min(peers['once_s']):.2f}-"
           f"{max(peers['once_s']):.2f} | {peers['once_fps']:.1f} |"] if once else []),
        f"| Storm, plain, frame loop | {min(peers['storm_s']):.2f}-"
        f"{max(peers['storm_s']):.2f} | {peers['storm_fps']:.1f} |", "",
        f"usdwrinkle's lead: {peers['lead']:.2f}x (rounds, ours / Storm's: {rounds})" +
        (f"; {peers['lead_once']:.2f}x with `--no-shade-samples`, which shades every pixel "
         "once (render's default shades each multisample where folds turn the normal "
         "within the pixel, so that they are averaged over it, as Storm's texture "
         "filtering averages a map)." if once else ".")]
