"""Hostile inputs and environments (issue 16): every class ends in a one-line error with
exit 2, or a warning and a correct result. Each test makes its hostile input at run time."""
from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux

from usdwrinkle.app.frames import frame_path, parse_frame_spec
from usdwrinkle.cli.main import main
from usdwrinkle.usd import schema

from conftest import grid_sheet
from helpers import point_cache_stage, read_until, scratch_frames_since

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
SHIRT_MESH = "/World/Arm/Sleeve"


# -- helpers ------------------------------------------------------------------------------
def sheet_stage(path: Path, frames=(1, 2, 3), edit=None) -> Path:
    """A small compressed sheet (point cache, WrinkleAPI) written to ``path``."""
    points, counts, indices = grid_sheet(9, 9, 2.0)
    posed = {}
    for f in frames:
        squeeze = points.copy()
        squeeze[:, 0] *= 1.0 - 0.1 * f
        posed[f] = squeeze
    stage = point_cache_stage(points, posed, counts, indices, width=0.5)
    if edit is not None:
        edit(stage)
    stage.GetRootLayer().Export(str(path))
    return path


def shirt_copy(tmp_path: Path, edit=None, name="shirt.usda") -> Path:
    """The shirt sample (and its texture) copied, with an optional edit of its root layer."""
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures", dirs_exist_ok=True)
    target = tmp_path / name
    shutil.copy(SAMPLES / "shirt.usda", target)
    if edit is not None:
        stage = Usd.Stage.Open(str(target))
        edit(stage)
        stage.GetRootLayer().Save()
    return target


def one_error(text: str) -> str:
    """The single 'usdwrinkle: error:' line of stderr text, with no raw library lines."""
    lines = [line for line in text.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("usdwrinkle: error: ")]
    assert len(errors) == 1, lines
    stray = [line for line in lines if not line.startswith("usdwrinkle: ")
             and "%|" not in line]  # tqdm bars are ours
    assert not stray, stray
    return errors[0]


def cli(args, timeout=120, cwd=None) -> subprocess.CompletedProcess:
    """The CLI as a separate process (for cases that could block or crash)."""
    return subprocess.run([sys.executable, "-m", "usdwrinkle", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, cwd=cwd)


def leftovers(folder: Path) -> list[str]:
    """Temporary files (ours: '.NAME.*.tmp.EXT', probes, scratch frames) under ``folder``."""
    return [p.name for p in folder.rglob(".*") if p.is_file()]


@contextlib.contextmanager
def tmpfs(path: Path, options: str):
    """A small tmpfs at ``path`` (root only); skips the test where mounting is impossible."""
    path.mkdir(parents=True, exist_ok=True)
    result = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)],
                            capture_output=True, text=True)
    if result.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({result.stderr.strip() or 'not root'})")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


# -- 1. silent corruption -----------------------------------------------------------------
@pytest.mark.parametrize("ext", ["png", "jpg", "exr"])
def test_full_disk_is_an_error_and_earlier_frames_stay_whole(gl_context, tmp_path, capsys, ext):
    started = time.time()
    stage = shirt_copy(tmp_path)
    with tmpfs(tmp_path / "disk", "size=400k") as disk:
        code = main(["render", str(stage), str(disk / f"f.####.{ext}"), "--frames", "1:40",
                     "--width", "320", "--quiet"])
        assert code == 2
        line = one_error(capsys.readouterr().err)
        assert "No space left on device" in line, line
        frames = sorted(disk.glob(f"f.*.{ext}"))
        assert len(frames) < 40
        for frame in frames:  # every committed frame decodes whole
            buf = oiio.ImageBuf(str(frame))
            assert buf.get_pixels(oiio.FLOAT) is not None, frame
            assert buf.spec().width == 320
        assert not leftovers(disk)
    assert not scratch_frames_since(started)


def test_skip_existing_renders_truncated_frames_again(gl_context, tmp_path, capsys):
    stage = shirt_copy(tmp_path)
    out = tmp_path / "out"
    assert main(["render", str(stage), str(out / "f.####.png"), "--frames", "1:3",
                 "--width", "64", "--quiet"]) == 0
    good = (out / "f.0001.png").read_bytes()
    (out / "f.0002.png").write_bytes(good[: len(good) // 2])  # truncated, as a full disk did
    (out / "f.0003.png").write_bytes(b"")
    mtime = (out / "f.0001.png").stat().st_mtime_ns
    assert main(["render", str(stage), str(out / "f.####.png"), "--frames", "1:3",
                 "--width", "64", "--quiet", "--skip-existing"]) == 0
    assert (out / "f.0001.png").stat().st_mtime_ns == mtime  # whole: skipped
    for name in ("f.0002.png", "f.0003.png"):
        assert oiio.ImageBuf(str(out / name)).get_pixels(oiio.FLOAT) is not None


def add_camera(stage, **values):
    cam = UsdGeom.Camera.Define(stage, "/World/Cam")
    cam.AddTranslateOp().Set(Gf.Vec3d(0, 0, 10))
    for name, value in values.items():
        cam.GetPrim().GetAttribute(name).Set(value)


def add_light(stage, **values):
    light = UsdLux.DistantLight.Define(stage, "/World/Key")
    for name, value in values.items():
        light.GetPrim().GetAttribute(name).Set(value)


def add_scale(stage, scale):
    UsdGeom.Xformable(stage.GetPrimAtPath("/World")).AddScaleOp(
        UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*scale))


NON_FINITE_SCENES = {
    "camera focalLength nan": (lambda s: add_camera(s, focalLength=float("nan")),
                               "camera focalLength nan must be finite and > 0 (/World/Cam"),
    "camera aperture 0": (lambda s: add_camera(s, horizontalAperture=0.0),
                          "camera horizontalAperture 0.0 must be finite and > 0"),
    "light intensity nan": (lambda s: add_light(s, **{"inputs:intensity": float("nan")}),
                            "light intensity is not finite (/World/Key.inputs:intensity"),
    "light intensity inf": (lambda s: add_light(s, **{"inputs:intensity": float("inf")}),
                            "light intensity is not finite (/World/Key.inputs:intensity"),
    # Storm clamps exposure to +-50 stops: with intensity 1e25 that still overflows
    "light exposure 1024": (lambda s: add_light(s, **{"inputs:exposure": 1024.0,
                                                      "inputs:intensity": 1e25}),
                            "exceeds 1e+30"),
    "transform nan": (lambda s: UsdGeom.Xformable(s.GetPrimAtPath("/World")).AddTranslateOp()
                      .Set(Gf.Vec3d(float("nan"), 0, 0)), "transform is not finite"),
    "transform 1e39": (lambda s: add_scale(s, (1e39, 1, 1)), "transform is not finite"),
    "scale 1e30": (lambda s: add_scale(s, (1e30, 1e30, 1e30)),
                   f"beyond +-1e+15 (the GPU's float32 range); check the units and the "
                   f"transforms ({SHIRT_MESH}.xformOp"),
    "profile 3e38": (lambda s: s.GetPrimAtPath(SHIRT_MESH).CreateAttribute(
        schema.HEIGHT_PROFILE, Sdf.ValueTypeNames.FloatArray).Set([3e38, -3e38, 3e38]),
        "profile samples must lie within +-1000"),
    "amplitude scale 3e38": (lambda s: s.GetPrimAtPath(SHIRT_MESH).CreateAttribute(
        schema.AMPLITUDE_SCALE, Sdf.ValueTypeNames.Float).Set(3e38),
        "amplitude scale must be at most 1000"),
}


@pytest.mark.parametrize("case", sorted(NON_FINITE_SCENES))
def test_non_finite_scene_data_is_refused(gl_context, tmp_path, capsys, case):
    edit, fragment = NON_FINITE_SCENES[case]
    stage = shirt_copy(tmp_path, edit)
    camera = ["--camera", "/World/Cam"] if case.startswith("camera") else []
    code = main(["render", str(stage), str(tmp_path / "out" / "f.####.exr"), "--frames", "2",
                 "--width", "48", "--quiet", *camera])
    assert code == 2
    assert fragment in one_error(capsys.readouterr().err)
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").iterdir())
    if case in ("scale 1e30", "profile 3e38"):  # nor does a bake write a layer
        code = main(["bake", str(stage), str(tmp_path / "b.usda"), "--frames", "1:2",
                     "--quiet"])
        assert code == 2 and not (tmp_path / "b.usda").exists()
        assert fragment in one_error(capsys.readouterr().err)


def test_apply_q_with_huge_components_keeps_its_direction(tmp_path):
    stage = shirt_copy(tmp_path)
    assert main(["apply", str(stage), SHIRT_MESH, "--q", "1e308,1e308,0:1"]) == 0
    other = shirt_copy(tmp_path / "b")
    assert main(["apply", str(other), SHIRT_MESH, "--q", "1,1,0:1"]) == 0
    opened = [Usd.Stage.Open(str(path)) for path in (stage, other)]
    q, reference = (np.asarray(s.GetPrimAtPath(SHIRT_MESH).GetAttribute(schema.Q).Get())
                    for s in opened)
    assert np.all(np.isfinite(q))
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(q, reference, atol=1e-6)


# -- 2. inputs overwritten ----------------------------------------------------------------
def test_render_onto_the_stages_texture_is_refused(gl_context, tmp_path, capsys):
    stage = shirt_copy(tmp_path)
    texture = tmp_path / "textures" / "plaid.png"
    before = texture.read_bytes()
    assert main(["render", str(stage), str(texture), "--frames", "1", "--width", "32"]) == 2
    assert "is an input of the stage" in one_error(capsys.readouterr().err)
    assert texture.read_bytes() == before
    # a hard link to the texture is the texture
    os.link(texture, tmp_path / "linked.png")
    assert main(["render", str(stage), str(tmp_path / "linked.png"), "--frames", "1",
                 "--width", "32"]) == 2
    assert texture.read_bytes() == before


def variant_layout(tmp_path: Path) -> Path:
    """A stage whose unselected variant references b.usda, and that sublayers a layer
    that does not exist yet."""
    sheet_stage(tmp_path / "a.usda")
    sheet_stage(tmp_path / "b.usda")
    root = tmp_path / "root.usda"
    root.write_text("""#usda 1.0
(
    subLayers = [@./later.usda@]
)
def Xform "Asset" (
    variants = { string look = "a" }
    prepend variantSets = "look"
)
{
    variantSet "look" = {
        "a" (
            references = @./a.usda@</Sheet>
        ) {
        }
        "b" (
            references = @./b.usda@</Sheet>
        ) {
        }
    }
}
""")
    return root


@pytest.mark.parametrize("target", ["b.usda", "later.usda"])
def test_bake_onto_unselected_variant_or_future_sublayer_is_refused(gl_context, tmp_path,
                                                                    capsys, target):
    root = variant_layout(tmp_path)
    before = (tmp_path / "b.usda").read_bytes()
    assert main(["bake", str(root), str(tmp_path / target), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "is an input of the stage" in one_error(err)
    assert (tmp_path / "b.usda").read_bytes() == before
    assert not (tmp_path / "later.usda").exists()
    # the missing sublayer is reported as our warning, not USD's raw diagnostic
    assert "usdwrinkle: warning: Could not load sublayer @" in err and "later.usda" in err
    assert "_ReportErrors" not in err


def test_apply_through_a_symlink_edits_the_real_file(tmp_path):
    real = shirt_copy(tmp_path)
    link = tmp_path / "link.usda"
    link.symlink_to(real.name)
    assert main(["apply", str(link), SHIRT_MESH, "--width", "0.3"]) == 0
    assert link.is_symlink()
    opened = Usd.Stage.Open(str(real))
    width = opened.GetPrimAtPath(SHIRT_MESH).GetAttribute(schema.WIDTH).Get()
    assert list(width) == [pytest.approx(0.3)]


# -- 3. lost frames -----------------------------------------------------------------------
def test_sub_frames_that_share_a_name_are_refused(gl_context, tmp_path, capsys):
    stage = shirt_copy(tmp_path)
    assert main(["render", str(stage), str(tmp_path / "f.####.png"), "--frames",
                 "1.0004,1.0001", "--width", "32"]) == 2
    assert "would both be written to" in one_error(capsys.readouterr().err)
    assert main(["render", str(stage), str(tmp_path / "g.####.png"), "--frames",
                 "1.0004,1.9996", "--width", "32", "--quiet"]) == 0
    assert sorted(p.name for p in tmp_path.glob("g.*")) == ["g.0001.000.png", "g.0002.000.png"]
    assert frame_path("x.####.exr", 2.0) == "x.0002.exr"
    assert frame_path("x.####.exr", 1.25) == "x.0001.250.exr"
    assert frame_path("x.####.exr", -1.5) == "x.-0001.500.exr"


# -- 4. native crashes --------------------------------------------------------------------
@pytest.mark.parametrize("args,fragment", [
    (["--width", "1073741824", "--height", "2"], "GL_MAX_TEXTURE_SIZE"),
    (["--width", "64", "--samples", "4096"], "GL_MAX_SAMPLES"),
    (["--width", "16384", "--height", "16384", "--samples", "4"],
     "GiB of memory are available"),
])
def test_frame_sizes_beyond_the_limits_are_refused(tmp_path, args, fragment):
    from usdwrinkle.process.memory import available_memory

    if fragment.startswith("GiB"):  # the largest frame GL 4.5 guarantees, 4 samples
        needed = 16384 * 16384 * (52 * 5 + 96)
        available = available_memory()
        if available is None or available > needed:
            pytest.skip("this machine has the memory for the largest frame GL allows")
    stage = shirt_copy(tmp_path)
    result = cli(["render", stage, tmp_path / "f.####.png", "--frames", "1", *args])
    assert result.returncode == 2, result.stderr
    assert fragment in one_error(result.stderr)


# -- 5. hangs and blow-ups ----------------------------------------------------------------
@pytest.mark.parametrize("where", ["stage", "sublayer", "texture"])
def test_fifos_are_refused_without_blocking(tmp_path, where):
    fifo = tmp_path / "fifo.usda"
    os.mkfifo(fifo)
    if where == "stage":
        stage = fifo
    elif where == "sublayer":
        stage = tmp_path / "root.usda"
        stage.write_text('#usda 1.0\n(\n    subLayers = [@./fifo.usda@]\n)\n')
    else:
        stage = shirt_copy(tmp_path)
        texture = tmp_path / "textures" / "plaid.png"
        texture.unlink()
        os.mkfifo(texture)
    result = cli(["render", stage, tmp_path / "f.png", "--width", "32"], timeout=60)
    assert result.returncode == 2, result.stderr
    assert "is a FIFO, not a regular file" in one_error(result.stderr)
    result = cli(["check", stage], timeout=60)
    assert result.returncode == 2
    assert "is a FIFO" in one_error(result.stderr)


def test_relax_iterations_beyond_the_cap(gl_context, tmp_path, capsys):
    stage = sheet_stage(tmp_path / "s.usda", edit=lambda s: s.GetPrimAtPath("/Sheet")
                        .CreateAttribute(schema.RELAX_ITERATIONS, Sdf.ValueTypeNames.Int)
                        .Set(2_000_000_000))
    assert main(["render", str(stage), str(tmp_path / "f.####.png"), "--width", "32"]) == 2
    assert "relax iterations must be in 0..10,000 (/Sheet.wrinkle:relaxIterations)" in \
        one_error(capsys.readouterr().err)
    assert main(["render", str(stage), str(tmp_path / "f.####.png"), "--width", "32",
                 "--relax-iterations", "10001"]) == 2
    assert "--relax-iterations must be in 0..10,000" in one_error(capsys.readouterr().err)


def test_check_reports_the_relax_cap(tmp_path, capsys):
    stage = sheet_stage(tmp_path / "s.usda", edit=lambda s: s.GetPrimAtPath("/Sheet")
                        .CreateAttribute(schema.RELAX_ITERATIONS, Sdf.ValueTypeNames.Int)
                        .Set(2_000_000_000))
    assert main(["check", str(stage)]) == 1
    out = capsys.readouterr().out
    assert "/Sheet.wrinkle:relaxIterations: relax iterations must be in 0..10,000" in out


@pytest.mark.parametrize("spec,fragment", [
    ("inf", "frame inf is not a finite time code"),
    ("1e308", "is not a finite time code within +-1e+09"),
    ("1:100000x0.001", "names more than 100,000 frames"),
    ("1:200000", "names more than 100,000 frames"),
    ("1:", "bad FrameSpec '1:'"),  # crashed the process inside UsdUtils (found by fuzzing)
    ("1:5x-1", "stride -1 does not lead from 1 to 5"),
])
def test_frame_specs_are_bounded_before_they_are_listed(tmp_path, capsys, spec, fragment):
    stage = sheet_stage(tmp_path / "s.usda")
    assert main(["render", str(stage), str(tmp_path / "f.####.png"), "--frames", spec]) == 2
    assert fragment in one_error(capsys.readouterr().err)


def test_a_long_frame_spec_is_parsed_in_linear_time():
    frames = parse_frame_spec("1:100000")  # was quadratic: 80 s
    assert len(frames) == 100_000 and frames[0] == 1.0 and frames[-1] == 100_000.0
    assert parse_frame_spec("1:3,2,3,5") == [1.0, 2.0, 3.0, 5.0]


def test_history_is_capped(gl_context, tmp_path, capsys):
    stage = sheet_stage(tmp_path / "s.usda")
    assert main(["render", str(stage), str(tmp_path / "f.####.png"), "--frames", "900000",
                 "--width", "32"]) == 2
    assert "more than 100,000 frames of history are refused" in \
        one_error(capsys.readouterr().err)
    assert main(["render", str(stage), str(tmp_path / "f.####.png"), "--frames", "1",
                 "--history-start=-inf"]) == 2
    assert "--history-start -inf is not a finite time code" in \
        one_error(capsys.readouterr().err)


def test_too_many_points_are_refused_before_triangulation(tmp_path, capsys, monkeypatch):
    from usdwrinkle.scene import stage as stage_module

    def never(*args, **kwargs):
        raise AssertionError("triangulated a mesh that is over the limit")

    monkeypatch.setattr(stage_module, "MAX_POINTS", 50)
    monkeypatch.setattr(stage_module, "build_topology", never)
    stage = sheet_stage(tmp_path / "s.usda")  # 81 points
    assert main(["bake", str(stage), str(tmp_path / "b.usda")]) == 2
    assert "mesh too large: 81 points, usdwrinkle handles fewer than 50 per mesh " \
           "(/Sheet.primvars:rest)" in one_error(capsys.readouterr().err)


# -- 6. input problems that were exit 3 ---------------------------------------------------
def retype(name, type_name, value):
    """Author an attribute of WrinkleAPI with another type (the schema's type is fixed,
    so through the layer's specs)."""
    def edit(stage):
        spec = stage.GetRootLayer().GetPrimAtPath("/Sheet")
        if name in spec.properties:
            spec.RemoveProperty(spec.properties[name])
        Sdf.AttributeSpec(spec, name, type_name).default = value
    return edit


def time_range(start, end):
    def edit(stage):
        stage.SetStartTimeCode(start)
        stage.SetEndTimeCode(end)
    return edit


STAGE_CASES = {
    "string amplitude scale": (retype(schema.AMPLITUDE_SCALE, Sdf.ValueTypeNames.String, "x"),
                               "wrinkle:amplitudeScale must be a float, not string"),
    "float[] q": (retype(schema.Q, Sdf.ValueTypeNames.FloatArray, [1.0, 2.0]),
                  "primvars:wrinkle:q must be a vector3f[] array, not float[]"),
    "string[] width": (retype(schema.WIDTH, Sdf.ValueTypeNames.StringArray, ["a"]),
                       "primvars:wrinkle:width must be a float[] array or a float"),
    "scalar profile": (retype(schema.HEIGHT_PROFILE, Sdf.ValueTypeNames.Float, 1.0),
                       "wrinkle:heightProfile must be a float[] array, not float"),
    "start after end": (time_range(5, 1), "endTimeCode is before its startTimeCode"),
    "nan start": (time_range(float("nan"), 3), "frame range is not finite"),
    "1e12 end": (time_range(1, 1e12), "frame range is not finite within +-1e+09"),
}


@pytest.mark.parametrize("case", sorted(STAGE_CASES))
def test_stage_values_of_the_wrong_kind(gl_context, tmp_path, capsys, case):
    edit, fragment = STAGE_CASES[case]
    stage = sheet_stage(tmp_path / "s.usda", edit=edit)
    for command in (["render", str(stage), str(tmp_path / "f.####.png"), "--width", "32"],
                    ["bake", str(stage), str(tmp_path / "b.usda")]):
        assert main(command) == 2, case
        assert fragment in one_error(capsys.readouterr().err)
    if "must be" in fragment:  # a type: also a finding of check
        assert main(["check", str(stage)]) == 1
        out = capsys.readouterr().out
        assert fragment in out and "usdWrinkleValidators:WrinkleAPIChecker" in out


def write_bytes(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def test_unreadable_files_are_one_line_errors(tmp_path, capsys):
    bad = write_bytes(tmp_path / "bad.usda", b'#usda 1.0\ndef Xform "A" { \xff }\n')
    assert main(["check", str(bad)]) == 2
    assert "it is not UTF-8 text" in one_error(capsys.readouterr().err)
    syntax = write_bytes(tmp_path / "syntax.usda", b'#usda 1.0\ndef Xform "A" {\n  float x =\n}\n')
    assert main(["check", str(syntax)]) == 2
    # USD's file:line:column
    assert f"{syntax}:3:3: Expected }}" in one_error(capsys.readouterr().err)
    corrupt = write_bytes(tmp_path / "corrupt.usdz", b"PK\x03\x04" + b"\x00" * 200)
    assert main(["check", str(corrupt)]) == 2
    assert "cannot open" in one_error(capsys.readouterr().err)


def test_zero_byte_texture_warns_and_renders_untextured(gl_context, tmp_path, capsys):
    stage = shirt_copy(tmp_path)
    (tmp_path / "textures" / "plaid.png").write_bytes(b"")
    assert main(["render", str(stage), str(tmp_path / "f.png"), "--frames", "1", "--width",
                 "32", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "usdwrinkle: warning: cannot decode texture" in err and "the file is empty" in err
    assert oiio.ImageBuf(str(tmp_path / "f.png")).get_pixels(oiio.FLOAT) is not None


def test_device_texture_is_refused(tmp_path, capsys):
    stage = shirt_copy(tmp_path)
    text = stage.read_text().replace("./textures/plaid.png", "/dev/zero")
    stage.write_text(text)
    assert main(["check", str(stage)]) == 2
    assert "'/dev/zero' (used by" in one_error(capsys.readouterr().err)


@contextlib.contextmanager
def read_only_folder(path: Path):
    """A folder that cannot be written, also by root (a read-only mount), else by mode."""
    path.mkdir()
    if os.geteuid() == 0:
        with tmpfs(path, "ro,size=64k"):
            yield path
    else:
        path.chmod(0o555)
        try:
            yield path
        finally:
            path.chmod(0o755)


def test_outputs_that_cannot_be_written(gl_context, tmp_path, capsys):
    stage = shirt_copy(tmp_path)
    with read_only_folder(tmp_path / "ro") as folder:
        assert main(["render", str(stage), str(folder / "f.####.png"), "--frames", "1:2",
                     "--width", "32"]) == 2
        line = one_error(capsys.readouterr().err)
        assert "cannot write" in line and ("Read-only" in line or "denied" in line), line
        assert main(["bake", str(stage), str(folder / "b.usda"), "--frames", "1"]) == 2
        assert "cannot write" in one_error(capsys.readouterr().err)
    (tmp_path / "dir" / "f.0001.png").mkdir(parents=True)
    assert main(["render", str(stage), str(tmp_path / "dir" / "f.####.png"), "--frames", "1",
                 "--width", "32"]) == 2
    assert "it is a folder" in one_error(capsys.readouterr().err)
    (tmp_path / "file").write_text("x")
    assert main(["render", str(stage), str(tmp_path / "file" / "f.####.png"), "--frames", "1",
                 "--width", "32"]) == 2
    assert "a part of its folder path is a file" in one_error(capsys.readouterr().err)
    (tmp_path / "notes.usda").write_text("not a layer\n")
    assert main(["apply", str(stage), SHIRT_MESH, "--width", "0.2", "-o",
                 str(tmp_path / "notes.usda")]) == 2
    assert "is not a USD layer" in one_error(capsys.readouterr().err)
    assert (tmp_path / "notes.usda").read_text() == "not a layer\n"


def test_immutable_output_is_an_error(gl_context, tmp_path, capsys):
    stage = shirt_copy(tmp_path)
    out = tmp_path / "f.png"
    out.write_bytes(b"old")
    if subprocess.run(["chattr", "+i", str(out)], capture_output=True).returncode != 0:
        pytest.skip("chattr +i is not available here (needs root and a supporting filesystem)")
    try:
        assert main(["render", str(stage), str(out), "--frames", "1", "--width", "32"]) == 2
        assert "cannot write" in one_error(capsys.readouterr().err)
        assert out.read_bytes() == b"old"
    finally:
        subprocess.run(["chattr", "-i", str(out)], check=False)
    assert not leftovers(tmp_path)


def test_memory_error_is_exit_2(gl_context, tmp_path, capsys, monkeypatch):
    from usdwrinkle.scene import stage as stage_module

    def exhausted(*args, **kwargs):
        raise MemoryError()

    monkeypatch.setattr(stage_module, "build_topology", exhausted)
    stage = sheet_stage(tmp_path / "s.usda")
    assert main(["render", str(stage), str(tmp_path / "f.####.png")]) == 2
    assert "out of memory" in one_error(capsys.readouterr().err)


# -- 7. messages and signals --------------------------------------------------------------
def test_sighup_during_a_bake_leaves_no_temporary_file(tmp_path):
    stage = shirt_copy(tmp_path)
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "usdwrinkle", "bake", str(stage),
                             str(out / "b.usdc"), "--frames", "1:2000"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    # signal on an observed event, not after a guessed delay: the progress report says
    # that frames of the bake's loop are done
    seen = read_until(proc.stderr, re.compile(rb"[^0-9][1-9][0-9]*/2000 "), timeout=300)
    proc.send_signal(signal.SIGHUP)
    _, rest = proc.communicate(timeout=120)
    err = (seen + rest).decode("utf-8", "replace")
    assert proc.returncode == 143, err
    assert "usdwrinkle: terminated; the layer was not written" in err
    assert not out.exists() or not list(out.iterdir())


def test_an_interrupted_check_says_nothing_of_frames(tmp_path):
    stage = sheet_stage(tmp_path / "s.usda")
    code = """
import sys
from usdwrinkle.app import check
from usdwrinkle.cli import main
def interrupted(stage):
    raise KeyboardInterrupt
check.collect = interrupted
sys.exit(main.main(["check", sys.argv[1]]))
"""
    result = subprocess.run([sys.executable, "-c", code, str(stage)], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 130
    assert result.stderr.strip() == "usdwrinkle: interrupted"
