"""The same shot through usdwrinkle and through a real client, side by side.

Both renderers look through one camera: the stage's own, or, for a stage without one,
a layer that sublayers the stage and adds usdwrinkle's framing camera (usdrecord's
placement over the whole shot's bounds; usdrecord itself frames each frame's bounds).
Stages without lights are compared with usdview's camera light on, since that is how
usdview shows them and how usdwrinkle lights them; stages with lights without it, so
that the stage's own lights are compared.
"""
from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from . import REPO, storm
from .compare import Match, compare, side_by_side

CORPUS = Path(os.environ.get("USDWRINKLE_CORPUS", REPO.parent / "shared" / "corpus"))
SAMPLES = REPO / "sample_stages"
CAMERA_PATH = "/UsdWrinkleFramingCamera"


@dataclass(frozen=True)
class Shot:
    name: str
    stage: Path
    frames: tuple
    all_meshes: bool = False
    #: image width, when the shot needs more than the comparison's (a small figure in a
    #: wide framing: its texture's filtering would dominate the difference)
    width: int | None = None


#: the plain-frame comparison of issue 24: the sample stages, CesiumMan and two of
#: Pixar's UsdSkel imaging stages (polygonal without normals: faceted; catmullClark:
#: smooth), each at two frames
PLAIN_SHOTS = (
    Shot("shirt", SAMPLES / "shirt.usda", (1, 24)),
    Shot("zeppelin", SAMPLES / "zeppelin.usda", (1, 24)),
    Shot("curtain", SAMPLES / "curtain.usda", (1, 24)),
    Shot("pull", SAMPLES / "pull.usda", (1, 24)),
    Shot("pillow", SAMPLES / "pillow.usda", (1, 24)),
    Shot("CesiumMan", CORPUS / "usd-wg" / "CesiumMan.usdz", (1, 24), all_meshes=True,
         width=640),
    Shot("test_lbs", CORPUS / "openusd-usdskel" / "test_lbs.usda", (1, 60)),
    Shot("arm", CORPUS / "openusd-usdskel" / "arm.usda", (1, 5)),
)


def _usdwrinkle(*args) -> None:
    done = subprocess.run([sys.executable, "-m", "usdwrinkle", *map(str, args)],
                          capture_output=True, text=True, timeout=900)
    if done.returncode != 0:
        raise RuntimeError(f"usdwrinkle {' '.join(map(str, args))}: {done.stderr.strip()}")


def shared_camera(stage_path: Path, folder: Path) -> tuple[Path, str]:
    """(the stage both renderers open, the camera both look through)."""
    from pxr import Sdf, Usd, UsdGeom

    from usdwrinkle.scene.camera import find_camera, framing_gf_camera
    from usdwrinkle.scene.stage import StageSceneDelegate

    stage = Usd.Stage.Open(str(stage_path))
    camera = find_camera(stage, None)
    if camera is not None:
        return stage_path, str(camera.GetPath())
    scene = StageSceneDelegate(stage)
    gf_camera = framing_gf_camera(*scene.bounds(), scene.up_axis, 16.0 / 9.0)
    wrapper = folder / f"{stage_path.stem}.framed.usda"
    layer = Sdf.Layer.CreateNew(str(wrapper))
    layer.subLayerPaths.append(str(stage_path))
    root = stage.GetRootLayer().pseudoRoot
    for key in ("upAxis", "metersPerUnit", "timeCodesPerSecond", "startTimeCode",
                "endTimeCode"):
        if root.HasInfo(key):
            layer.pseudoRoot.SetInfo(key, root.GetInfo(key))
    layer.Save()
    framed = Usd.Stage.Open(layer)
    cam = UsdGeom.Camera.Define(framed, CAMERA_PATH)
    cam.SetFromCamera(gf_camera, Usd.TimeCode.Default())
    framed.GetRootLayer().Save()
    return wrapper, CAMERA_PATH


def over_layer(stage_path: Path, target: Path):
    """A new layer at ``target`` that sublayers ``stage_path`` (an over layer: the stage's
    paths hold) with its time and axis metadata; returns (stage on it, the layer)."""
    from pxr import Sdf, Usd

    layer = Sdf.Layer.CreateNew(str(target))
    layer.subLayerPaths.append(str(stage_path))
    source = Sdf.Layer.FindOrOpen(str(stage_path))  # held: its specs expire with it
    for key in ("upAxis", "metersPerUnit", "timeCodesPerSecond", "startTimeCode",
                "endTimeCode"):
        if source.pseudoRoot.HasInfo(key):
            layer.pseudoRoot.SetInfo(key, source.pseudoRoot.GetInfo(key))
    layer.Save()
    return Usd.Stage.Open(layer), layer


def flat_textures(stage, folder: Path, grey: float = 0.6) -> int:
    """Replace every UsdUVTexture's image by a 4x4 image of one ``grey`` (in the stage's
    edit target), so that texture filtering, which renderers and GL drivers do their own
    way, drops out of a comparison; returns how many were replaced."""
    import numpy as np
    import OpenImageIO as oiio
    from pxr import Sdf, UsdShade

    replaced = 0
    for prim in stage.Traverse():
        shader = UsdShade.Shader(prim)
        if not shader or shader.GetIdAttr().Get() != "UsdUVTexture":
            continue
        attr = prim.GetAttribute("inputs:file")
        if not attr or not attr.Get():
            continue
        flat = folder / f"{Path(stage.GetRootLayer().realPath).stem}.flat{replaced}.png"
        buf = oiio.ImageBuf(oiio.ImageSpec(4, 4, 3, "uint8"))
        buf.set_pixels(oiio.ROI(), np.full((4, 4, 3), grey, np.float32))
        buf.write(str(flat))
        attr.Set(Sdf.AssetPath(str(flat)))
        replaced += 1
    return replaced


def has_lights(stage_path: Path) -> bool:
    from pxr import Usd, UsdLux

    stage = Usd.Stage.Open(str(stage_path))  # held: its prims expire with it
    return any(prim.HasAPI(UsdLux.LightAPI) for prim in stage.Traverse())


@dataclass(frozen=True)
class Comparison:
    shot: Shot
    frame: float
    ours: Path
    storm: Path
    match: Match


def compare_plain_frames(shots, folder: Path, width: int = 480,
                         wrinkles: bool = False) -> list[Comparison]:
    """Render each shot's frames through usdwrinkle and Storm, same camera and size;
    writes ``NAME.FRAME.{ours,storm,sbs}.png`` into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    jobs, pending = [], []
    for shot in shots:
        stage, camera = shared_camera(shot.stage, folder)
        lit = has_lights(shot.stage)
        shot_width = shot.width or width
        for frame in shot.frames:
            base = folder / f"{shot.name}.{frame:g}"
            ours = base.with_suffix(base.suffix + ".ours.png")
            _usdwrinkle("render", stage, ours, "--frames", f"{frame:g}", "--width", shot_width,
                        "--camera", camera, "--quiet", *(() if wrinkles else ("--no-wrinkles",)),
                        *(("--all-meshes",) if shot.all_meshes else ()))
            theirs = base.with_suffix(base.suffix + ".storm.png")
            jobs.append({"stage": str(stage), "camera": camera, "frame": frame,
                         "width": shot_width, "out": str(theirs), "camera_light": not lit})
            pending.append((shot, frame, ours, theirs))
    results = storm(jobs)
    comparisons = []
    for shot, frame, ours, theirs in pending:
        if results[str(theirs)] != "ok":
            raise RuntimeError(f"Storm could not render {shot.name} at frame {frame:g}: "
                               f"{results[str(theirs)]}")
        side_by_side([ours, theirs], str(ours).replace(".ours.png", ".sbs.png"))
        comparisons.append(Comparison(shot, frame, ours, theirs, compare(ours, theirs)))
    return comparisons


if __name__ == "__main__":  # python -m realclients.shots OUT_FOLDER [NAME ...]
    out = Path(sys.argv[1])
    names = set(sys.argv[2:])
    for comparison in compare_plain_frames([s for s in PLAIN_SHOTS
                                            if not names or s.name in names], out):
        print(f"{comparison.shot.name:10s} {comparison.frame:4g}  {comparison.match}")
