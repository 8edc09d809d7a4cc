"""Outputs users can trust (issue 22): every file is the frame it names, or the run says
why in one line.

- Multi-frame identity: every file of a multi-frame run equals the same frame rendered
  alone, bit for bit in its stored pixels, for every format and writer mode, and on Dask.
- Faults injected: small tmpfs mounts for the output folder and for /dev/shm (in a mount
  namespace of the test's own), repeated stop signals, address-space limits.
"""
from __future__ import annotations

import os
import re
import resource
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import OpenEXR
import OpenImageIO as oiio
import pytest
from pxr import Sdf, Usd, UsdGeom, Vt

from usdwrinkle.cli.main import main

from helpers import read_until

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
SHIRT = str(SAMPLES / "shirt.usda")
FORMATS = ("png", "jpg", "tif", "exr")
#: a time-varying shot, large enough that an encode overlaps the next frame's draw
FRAMES, WIDTH = "1:10", 400


def stored_pixels(path: Path) -> dict:
    """A file's pixels as stored: {channel: array} (EXR through OpenEXR, each channel at
    its own precision; 8-bit formats as their codes)."""
    if path.suffix == ".exr":
        with OpenEXR.File(str(path)) as exr:
            return {name: np.array(channel.pixels) for name, channel in exr.channels().items()}
    buf = oiio.ImageBuf(str(path))
    pixels = buf.get_pixels(oiio.UINT8)
    assert pixels is not None and not buf.has_error, path
    return {"codes": pixels}


def same_pixels(a: Path, b: Path) -> bool:
    pa, pb = stored_pixels(a), stored_pixels(b)
    return pa.keys() == pb.keys() and all(
        pa[k].dtype == pb[k].dtype and np.array_equal(pa[k], pb[k], equal_nan=True) for k in pa)


def cli(*args, timeout=600, **kwargs):
    return subprocess.run([sys.executable, "-m", "usdwrinkle", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, **kwargs)


def one_error(text: str) -> str:
    lines = [line for line in text.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("usdwrinkle: error: ")]
    assert len(errors) == 1 and len(lines) == 1, lines
    return errors[0]


def hidden(folder: Path) -> list[str]:
    return [p.name for p in folder.rglob(".*")]


@pytest.fixture(scope="module")
def alone(tmp_path_factory, gl_context) -> dict:
    """Each frame of the shot rendered alone (its own run, with its preroll), per format,
    read back as soon as it is drawn (one readback buffer)."""
    out = tmp_path_factory.mktemp("alone")
    frames = {}
    first, last = (int(f) for f in FRAMES.split(":"))
    for fmt in FORMATS:
        for frame in range(first, last + 1):
            path = out / f"a.{frame:04d}.{fmt}"
            assert main(["render", SHIRT, str(path), "--frames", str(frame), "--width",
                         str(WIDTH), "--readback-buffers", "1", "--quiet"]) == 0
            frames[(fmt, frame)] = path
    return frames


def assert_every_file_is_its_frame(folder: Path, fmt: str, alone: dict) -> None:
    first, last = (int(f) for f in FRAMES.split(":"))
    written = sorted(folder.glob(f"m.*.{fmt}"))
    assert [p.name for p in written] == [f"m.{f:04d}.{fmt}" for f in range(first, last + 1)]
    wrong = [p.name for frame, p in zip(range(first, last + 1), written, strict=True)
             if not same_pixels(p, alone[(fmt, frame)])]
    assert not wrong, f"files that are not the frame they name: {wrong}"
    assert not hidden(folder)


#: writer threads and readback buffers: serial, the defaults, the most of each
WRITERS = [(0, 1), (0, 2), (1, 2), (2, 3), (None, None), (None, 8), (64, 2), (64, 8)]


@pytest.mark.parametrize(("fmt", "threads", "buffers"),
                         [(fmt, *writers) for fmt in ("png", "exr") for writers in WRITERS]
                         + [(fmt, *writers) for fmt in ("jpg", "tif")
                            for writers in ((None, None), (64, 8))])
def test_every_file_is_the_frame_it_names(gl_context, tmp_path, alone, fmt, threads, buffers):
    """Issue 22, finding 1: the overlapped writer put another frame's pixels in 8-bit
    files (a readback array reused while the writer still encoded from it). Issue 45: with
    the default (every core but one) and the most writer threads (64, 65 frames in
    flight) too, and with K readback buffers in flight (the default 2, and up to the
    most, 8, more than the shot's frames). Every combination for an 8-bit and a float
    format (PNG, EXR); JPEG and TIFF, two more 8-bit encoders, at the defaults and at the
    most in flight (all 32 took a minute of CI's 15: 2026-12-06)."""
    given = [] if threads is None else ["--write-threads", str(threads)]
    given += [] if buffers is None else ["--readback-buffers", str(buffers)]
    assert main(["render", SHIRT, str(tmp_path / f"m.####.{fmt}"), "--frames", FRAMES,
                 "--width", str(WIDTH), *given, "--quiet"]) == 0
    assert_every_file_is_its_frame(tmp_path, fmt, alone)


@pytest.mark.parametrize("per_file", ["1", "4"])
def test_every_exr_is_its_frame_with_openexrs_own_threads(gl_context, tmp_path, alone,
                                                          monkeypatch, per_file):
    """Issue 45: a GPU node's default compresses each EXR on 4 threads of OpenEXR's own
    (outputs/writer.exr_file_threads); here forced, with 4 writer threads."""
    monkeypatch.setenv("USDWRINKLE_EXR_THREADS", per_file)
    assert main(["render", SHIRT, str(tmp_path / "m.####.exr"), "--frames", FRAMES,
                 "--width", str(WIDTH), "--write-threads", "4", "--quiet"]) == 0
    assert_every_file_is_its_frame(tmp_path, "exr", alone)


@pytest.mark.slow
def test_every_dask_file_is_the_frame_it_names(gl_context, tmp_path, alone):
    """The same on a Dask cluster: baked once, chunks rendered from the bake on workers."""
    distributed = pytest.importorskip("distributed")
    import logging

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  silence_logs=logging.CRITICAL, dashboard_address=None,
                                  local_directory=str(tmp_path / "dask")) as cluster:
        for fmt in FORMATS:
            out = tmp_path / fmt
            assert main(["render", SHIRT, str(out / f"m.####.{fmt}"), "--frames", FRAMES,
                         "--width", str(WIDTH), "--dask", cluster.scheduler_address,
                         "--chunk", "3", "--quiet"]) == 0
            (out / "usdwrinkle_bake" / "shirt.wrinkles.usdc").unlink()
            (out / "usdwrinkle_bake").rmdir()
            assert_every_file_is_its_frame(out, fmt, alone)


# -- full mounts: the output folder, and the scratch memory ------------------------------
def in_mount_namespace(shell: str, timeout=600) -> subprocess.CompletedProcess:
    """Run ``shell`` as root in a mount namespace of its own (its tmpfs mounts are seen by
    nothing else); skips where that is not possible, saying why."""
    if shutil.which("unshare") is None:
        pytest.skip("needs unshare (util-linux) to mount a small tmpfs privately")
    probe = subprocess.run(["unshare", "-m", "true"], capture_output=True, text=True)
    if probe.returncode != 0:
        pytest.skip(f"cannot make a mount namespace here ({probe.stderr.strip()}); "
                    "the full-mount tests need root")
    return subprocess.run(["unshare", "-m", "sh", "-c", shell], capture_output=True,
                          text=True, timeout=timeout)


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_tiny_dev_shm_still_gives_whole_frames(gl_context, tmp_path, alone, fmt):
    """Finding 2: frames were encoded to a scratch file in /dev/shm; a full one gave
    truncated PNGs with exit 0 (libpng reports no write error). They are now encoded in
    an anonymous memory file, which no mount limits."""
    out = tmp_path / "out"
    result = in_mount_namespace(
        f"mount -t tmpfs -o size=16k tmpfs /dev/shm && exec {sys.executable} -m usdwrinkle "
        f"render {SHIRT} {out}/m.####.{fmt} --frames {FRAMES} --width {WIDTH} --quiet")
    assert result.returncode == 0, result.stderr
    assert_every_file_is_its_frame(out, fmt, alone)


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_full_output_folder_is_one_error_and_frames_before_it_are_whole(gl_context, tmp_path,
                                                                        fmt):
    out = tmp_path / "out"
    out.mkdir()
    result = in_mount_namespace(
        f"mount -t tmpfs -o size=512k tmpfs {out} && {sys.executable} -m usdwrinkle render "
        f"{SHIRT} {out}/m.####.{fmt} --frames 1:60 --history-start 1 --width {WIDTH} "
        "--quiet; code=$?; "
        f"{sys.executable} -c \"import sys, OpenImageIO as o, glob; "
        f"paths = sorted(glob.glob('{out}/*.{fmt}')); "
        "bad = [p for p in paths if o.ImageBuf(p).get_pixels(o.FLOAT) is None]; "
        f"hidden = glob.glob('{out}/.*'); "
        "print(len(paths), bad, hidden)\"; exit $code")
    assert result.returncode == 2, result.stderr
    assert "No space left on device" in one_error(result.stderr)
    count, bad, leftovers = result.stdout.split(" ", 2)
    assert 0 < int(count) < 60 and bad == "[]" and leftovers.strip() == "[]", result.stdout


@pytest.mark.parametrize("extra", [[], ["--maps", "normal", "--map-size", "512"],
                                   ["--geometry", "--levels", "2"]])
def test_a_bake_onto_a_full_disk_is_one_error_and_leaves_nothing(tmp_path, extra):
    out = tmp_path / "out"
    out.mkdir()
    result = in_mount_namespace(
        f"mount -t tmpfs -o size=100k tmpfs {out} && {sys.executable} -m usdwrinkle bake "
        f"{SHIRT} {out}/b.usdc --frames 1:24 --quiet {' '.join(extra)}; code=$?; "
        f"ls -A {out}; exit $code")
    assert result.returncode == 2, result.stderr
    assert "No space left on device" in one_error(result.stderr)
    assert result.stdout.strip() == ""  # no layer, no map folder, no temporary file


def test_skip_existing_renders_a_truncated_jpeg_again(gl_context, tmp_path):
    """Finding 6: libjpeg decodes a truncated JPEG (grey below the cut) and only says
    so; such a frame is not whole."""
    out = tmp_path / "out"
    assert main(["render", SHIRT, str(out / "f.####.jpg"), "--frames", "1:2", "--width", "96",
                 "--quiet"]) == 0
    data = (out / "f.0002.jpg").read_bytes()
    (out / "f.0002.jpg").write_bytes(data[: len(data) // 2])
    assert main(["render", SHIRT, str(out / "f.####.jpg"), "--frames", "1:2", "--width", "96",
                 "--quiet", "--skip-existing"]) == 0
    assert (out / "f.0002.jpg").read_bytes() == data


def test_stats_onto_a_frame_is_refused(gl_context, tmp_path, capsys):
    out = tmp_path / "f.0001.png"
    assert main(["render", SHIRT, str(tmp_path / "f.####.png"), "--frames", "1:2",
                 "--stats", str(out)]) == 2
    assert "--stats" in one_error(capsys.readouterr().err)
    assert not list(tmp_path.iterdir())


# -- stop signals and address space ------------------------------------------------------
def test_a_second_ctrl_c_during_the_cleanup_still_exits_130(gl_context, tmp_path):
    """Finding 9: a second SIGINT a few ms after the first landed in the cleanup (or the
    GL and thread teardown after it) and aborted the process."""
    for attempt, gap in enumerate((0.0, 0.003, 0.007, 0.02)):
        out = tmp_path / str(attempt)
        proc = subprocess.Popen(
            [sys.executable, "-m", "usdwrinkle", "render", SHIRT, str(out / "s.####.png"),
             "--frames", "1:400", "--width", "320"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        # any count from 3 to 399: tqdm may skip the single digits on a fast machine
        read_until(proc.stderr, re.compile(rb"[^0-9]([3-9]|[1-9][0-9]|[1-3][0-9][0-9])/400 "),
                   timeout=300)
        proc.send_signal(signal.SIGINT)
        if gap:
            import time

            time.sleep(gap)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 130, (gap, err[-500:])
        assert not hidden(out)
        for frame in out.glob("s.*.png"):
            assert oiio.ImageBuf(str(frame)).get_pixels(oiio.UINT8) is not None


def _address_space(limit: int):
    def apply():
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    return apply


@pytest.mark.parametrize("megabytes", [300, 1000])
def test_a_small_address_space_is_one_error(tmp_path, megabytes):
    """Finding 10: under ulimit -v every command segfaulted while USD built its schema
    registry; below what usdwrinkle needs it now refuses to start, in one line."""
    result = subprocess.run([sys.executable, "-m", "usdwrinkle", "render", SHIRT,
                             str(tmp_path / "f.png"), "--frames", "1"],
                            capture_output=True, text=True, timeout=120,
                            preexec_fn=_address_space(megabytes << 20))
    assert result.returncode == 2, result.stderr
    assert "address-space limit" in one_error(result.stderr)
    assert not list(tmp_path.iterdir())


def test_renders_and_bakes_under_a_2_gib_address_space(gl_context, tmp_path, alone):
    """At the documented floor the lean thread settings make every command work, with
    the same frames."""
    limit = _address_space(2 << 30)
    out = tmp_path / "out"
    result = subprocess.run([sys.executable, "-m", "usdwrinkle", "render", SHIRT,
                             str(out / "m.####.png"), "--frames", FRAMES, "--width",
                             str(WIDTH), "--quiet"], capture_output=True, text=True,
                            timeout=600, preexec_fn=limit)
    assert result.returncode == 0 and result.stderr == "", result.stderr
    assert_every_file_is_its_frame(out, "png", alone)
    result = subprocess.run([sys.executable, "-m", "usdwrinkle", "bake", SHIRT,
                             str(tmp_path / "b.usdc"), "--frames", "1:3", "--maps", "normal",
                             "--map-size", "512", "--quiet"], capture_output=True, text=True,
                            timeout=600, preexec_fn=limit)
    assert result.returncode == 0 and result.stderr == "", result.stderr


# -- user mistakes: one line and exit 2, never exit 3 ------------------------------------
@pytest.mark.parametrize("args, fragment", [
    (["render", SHIRT, "OUT/f.####.png", "--width", "wide"], "argument --width: invalid int"),
    (["render", SHIRT, "OUT/f.####.png", "--frames", "1:2x1e-320"], "more than 100,000"),
    (["render", SHIRT, "OUT/f.####.png", "--frames", "1", "--samples", "3"],
     "not a power of two"),
    (["apply", SHIRT, "--width", "text"], "argument --width: invalid float"),
    (["bake", SHIRT, "OUT/b.usda", "--maps", "normal", "--map-size", "text"],
     "argument --map-size"),
    (["render", SHIRT, "OUT/f.####.png", "--frames", "1:3", "--dask", "--workers", "100000"],
     "--workers must be in"),
    (["render", SHIRT, "OUT/f.####.png", "--frames", "100000", "--relax-iterations", "10000",
      "--history-start", "1"], "at most 2,000,000 are accepted"),
])
def test_user_mistakes_are_one_line_and_exit_2(tmp_path, args, fragment):
    out = tmp_path / "out"
    result = cli(*[str(a).replace("OUT", str(out)) for a in args])
    assert result.returncode == 2, result.stderr
    assert fragment in one_error(result.stderr)
    assert not out.exists() or not list(out.iterdir())  # no file (the probe may make the folder)


def test_negative_frames_are_frames_not_options(gl_context, tmp_path):
    out = tmp_path / "out"
    assert main(["render", SHIRT, str(out / "f.####.png"), "--frames", "-2:-1", "--width",
                 "64", "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["f.-0001.png", "f.-0002.png"]


def test_debug_is_taken_after_the_subcommand_too(tmp_path):
    result = cli("render", tmp_path / "missing.usda", tmp_path / "f.png", "--debug")
    assert result.returncode == 2
    assert "Traceback" in result.stderr and "usdwrinkle: error: stage file" in result.stderr


def test_demo_onto_a_file_and_a_deleted_working_folder(tmp_path):
    target = tmp_path / "file"
    target.write_text("mine")
    result = cli("demo", target)
    assert result.returncode == 2 and "it is a file" in one_error(result.stderr)
    assert target.read_text() == "mine"
    gone = tmp_path / "gone"
    gone.mkdir()
    code = ("import os, subprocess, sys; os.chdir(sys.argv[1]); os.rmdir(sys.argv[1]); "
            "r = subprocess.run([sys.executable, '-m', 'usdwrinkle', 'render', sys.argv[2], "
            "'f.png'], capture_output=True, text=True); print(r.returncode); "
            "sys.stderr.write(r.stderr)")
    result = subprocess.run([sys.executable, "-c", code, str(gone), SHIRT],
                            capture_output=True, text=True, timeout=120)
    assert result.stdout.strip() == "2"
    assert "current folder no longer exists" in one_error(result.stderr)


def test_a_closed_stdout_and_a_full_stderr_are_not_errors(gl_context, corpus, tmp_path):
    """Finding 12-13: 'usdwrinkle info | head' raised BrokenPipeError (exit 3); with
    stderr on /dev/full a render exited 1 and wrote no frame."""
    result = subprocess.run(f"{sys.executable} -m usdwrinkle info | head -c 10",
                            shell=True, capture_output=True, text=True, timeout=120,
                            executable="/bin/bash")
    assert result.stdout == "usdwrinkle" and result.stderr == ""
    out = tmp_path / "out"
    with open("/dev/full", "w") as full:
        code = subprocess.run([sys.executable, "-m", "usdwrinkle", "render",
                               str(corpus / "usd-wg" / "CesiumMan.usdz"),
                               str(out / "c.####.png"),
                               "--frames", "1:3", "--width", "64"],
                              stdout=subprocess.DEVNULL, stderr=full, timeout=300).returncode
    assert code == 0
    assert len(list(out.glob("c.*.png"))) == 3


# -- inputs -------------------------------------------------------------------------------
def test_bake_onto_a_missing_search_path_sublayer_is_refused(tmp_path):
    """Finding 8: '@later.usda@' (a search path, not anchored) that does not exist was
    anchored at the working folder, so a bake onto it from elsewhere was allowed and the
    stage then composed our layer inside itself."""
    shot = tmp_path / "shot" / "shot.usda"
    shot.parent.mkdir()
    layer = Sdf.Layer.CreateNew(str(shot))
    layer.subLayerPaths.append("later.usda")
    layer.Save()
    result = cli("bake", shot, shot.parent / "later.usda", "--all-meshes",
                 cwd=str(tmp_path))
    assert result.returncode == 2
    assert "is an input of the stage" in result.stderr.splitlines()[-1]
    assert sorted(p.name for p in shot.parent.iterdir()) == ["shot.usda"]


def test_a_stage_without_a_time_range_renders_its_default_time(gl_context, tmp_path, capsys):
    """Finding 14: 'frames nan and nan would both be written'. A shot that sublayers an
    animated asset (time ranges are not inherited) renders the default time, and says
    which --frames gives the asset's range."""
    shot = tmp_path / "shot.usda"
    layer = Sdf.Layer.CreateNew(str(shot))
    layer.subLayerPaths.append(SHIRT)
    layer.Save()
    assert main(["render", str(shot), str(tmp_path / "f.png"), "--width", "64"]) == 0
    err = capsys.readouterr().err
    assert "pass --frames 1:24" in err
    assert (tmp_path / "f.png").is_file()
    assert main(["render", str(shot), str(tmp_path / "g.####.png"), "--width", "64",
                 "--quiet"]) == 0
    assert (tmp_path / "g.default.png").is_file()


def test_a_time_sampled_width_is_its_first_sample_in_render_and_check(gl_context, tmp_path,
                                                                     capsys):
    """Finding 4: a width authored only as time samples fell back to the default width,
    and check said the stage was clean. It is read by the static rule (the default, else
    the first sample), equal to the same width authored as a default, and a width that
    changes over time is a warning in both."""
    def shot_with_width(name, author):
        path = tmp_path / name
        stage = Usd.Stage.Open(SHIRT)
        stage.GetRootLayer().Export(str(path))
        stage = Usd.Stage.Open(str(path))
        for prim in stage.Traverse():
            if prim.HasAPI("WrinkleAPI"):
                primvar = UsdGeom.PrimvarsAPI(prim).CreatePrimvar(
                    "wrinkle:width", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.constant)
                primvar.GetAttr().Clear()  # the sample's own width (a default)
                author(primvar.GetAttr())
        stage.Save()
        shutil.copytree(SAMPLES / "textures", tmp_path / "textures", dirs_exist_ok=True)
        return path

    sampled = shot_with_width("sampled.usda", lambda a: [a.Set(Vt.FloatArray([0.2]), t)
                                                         for t in (1, 24)])
    default = shot_with_width("default.usda", lambda a: a.Set(Vt.FloatArray([0.2])))
    for path in (sampled, default):
        assert main(["render", str(path), str(tmp_path / f"{path.stem}.png"), "--frames",
                     "24", "--width", "200", "--quiet"]) == 0
    assert same_pixels(tmp_path / "sampled.png", tmp_path / "default.png")
    changing = shot_with_width("changing.usda", lambda a: [a.Set(Vt.FloatArray([w]), t)
                                                           for t, w in ((1, 0.2), (24, 0.4))])
    capsys.readouterr()
    assert main(["render", str(changing), str(tmp_path / "c.png"), "--frames", "24",
                 "--width", "200", "--quiet"]) == 0
    assert "do not animate" in capsys.readouterr().err
    assert same_pixels(tmp_path / "c.png", tmp_path / "default.png")
    assert main(["check", str(changing)]) == 1
    assert "do not animate: its value at its first time sample (1)" in capsys.readouterr().out


def test_a_farm_chunk_without_baked_fields_says_it_computes_them(gl_context, tmp_path,
                                                                  capsys):
    """Finding 7: chunks of a bake without --all-meshes recomputed silently."""
    from usdwrinkle.authoring.builders import grid_sheet

    stage_path = tmp_path / "two.usda"
    stage = Usd.Stage.CreateNew(str(stage_path))
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(3)
    for index, name in enumerate(("Marked", "Plain")):
        points, counts, indices = grid_sheet(6, 6, 1.0)
        mesh = UsdGeom.Mesh.Define(stage, f"/World/{name}")
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray(counts.tolist()))
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(indices.tolist()))
        for frame in (1, 2, 3):
            posed = np.asarray(points, np.float32) * [1 - 0.1 * frame, 1, 1] + [index * 2, 0, 0]
            mesh.CreatePointsAttr().Set(Vt.Vec3fArray.FromNumpy(posed.astype(np.float32)),
                                        frame)
        if name == "Marked":
            mesh.GetPrim().ApplyAPI("WrinkleAPI")
    stage.Save()
    layer = tmp_path / "bake.usdc"
    assert main(["bake", str(stage_path), str(layer), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["render", str(layer), str(tmp_path / "f.####.png"), "--frames", "2:3",
                 "--all-meshes", "--width", "64", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "1 wrinkled mesh(es) have no baked wave fields in it; computing them here, with a " \
           "phase-history preroll from frame 1" in err and "/World/Plain" in err
    assert main(["render", str(layer), str(tmp_path / "g.####.png"), "--frames", "2:3",
                 "--width", "64", "--quiet"]) == 0
    assert "no baked wave fields" not in capsys.readouterr().err
    os.remove(layer)


def test_a_broken_installation_is_one_error_not_a_crash(tmp_path):
    """Issue 25: a shader that is missing (a broken install) or that the GL driver rejects
    raised ShaderError, which was not a UsdWrinkleError, so the run ended with exit 3 and
    'please report'. It is one line naming the shader file, exit 2."""
    script = ("import pathlib, sys\n"
              "import usdwrinkle.render.shaders as shaders\n"
              f"shaders.resource_dir = lambda name: pathlib.Path({str(tmp_path)!r})\n"
              "from usdwrinkle.cli.main import main\n"
              "sys.exit(main(sys.argv[1:]))\n")
    result = subprocess.run([sys.executable, "-c", script, "render", SHIRT,
                             str(tmp_path / "f.png"), "--frames", "1", "--width", "64"],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 2, result.stderr
    line = one_error(result.stderr)
    assert "shader" in line and ".glsl:0: shader file not found" in line, line
    assert not (tmp_path / "f.png").exists()


def test_a_shader_the_driver_rejects_names_its_file_and_line(gl_context, tmp_path):
    from usdwrinkle.process.errors import ShaderError, UsdWrinkleError
    from usdwrinkle.render.shaders import compute_shader

    (tmp_path / "broken.glsl").write_text(
        "#version 430\nlayout(local_size_x = 1) in;\nvoid main() {\n  undefined_call();\n}\n")
    with pytest.raises(ShaderError) as caught:
        compute_shader(gl_context, "broken.glsl", {}, root=tmp_path)
    assert isinstance(caught.value, UsdWrinkleError)
    assert caught.value.file == "broken.glsl" and caught.value.line == 4, caught.value
