"""Long shots and interruptions: flat memory, reused GPU resources, whole frames only."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from usdwrinkle.engine import WrinkleEngine

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"


def rss_bytes() -> int:
    with open("/proc/self/status") as handle:
        for line in handle:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS")


def test_200_frames_keep_memory_and_gpu_resources_flat(gl_context):
    engine = WrinkleEngine(str(SAMPLES / "zeppelin.usda"), ctx=gl_context)
    try:
        resources = None
        framebuffer = None
        after_warmup = None
        for frame in range(1, 201):
            engine.render_frame(float(frame), 96, 64)
            if frame == 20:
                after_warmup = rss_bytes()
                resources = {p: engine.mesh_resources(p) for p in engine.rprim_paths}
                framebuffer = engine.debug.framebuffer
        final = rss_bytes()
        assert final < after_warmup * 1.05, (after_warmup, final)
        # the GPU objects of frame 20 are the ones of frame 200: nothing re-created
        assert all(engine.mesh_resources(p) is r for p, r in resources.items())
        assert engine.debug.framebuffer is framebuffer
    finally:
        engine.release()


def launch(args, cwd):
    env = dict(os.environ)
    return subprocess.Popen([sys.executable, "-m", "usdwrinkle", *args], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def whole_frames(folder: Path, width: int):
    names = sorted(p.name for p in folder.iterdir())
    hidden = [n for n in names if n.startswith(".")]
    assert not hidden, hidden  # no temporary file survives
    for name in names:
        buf = oiio.ImageBuf(str(folder / name))
        spec = buf.spec()
        assert spec.width == width, name
        pixels = buf.get_pixels(oiio.FLOAT)
        assert pixels is not None and pixels.shape[:2] == (spec.height, spec.width), name
    return names


@pytest.mark.parametrize("sig,code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_interrupted_render_leaves_only_whole_frames(gl_context, tmp_path, sig, code):
    out = tmp_path / "frames"
    args = ["render", str(SAMPLES / "shirt.usda"), str(out / "s.####.exr"), "--frames", "1:400",
            "--width", "640", "--quiet"]
    proc = launch(args, tmp_path)
    deadline = time.time() + 120
    while time.time() < deadline and len(list(out.glob("s.*.exr"))) < 3:
        time.sleep(0.05)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == code, err
    assert "finished frames are intact" in err
    names = whole_frames(out, 640)
    assert 3 <= len(names) < 400
    # --skip-existing resumes the chunk, and the resumed frames equal a fresh render
    done = {n: (out / n).stat().st_mtime_ns for n in names}
    resume = subprocess.run([sys.executable, "-m", "usdwrinkle", "render",
                             str(SAMPLES / "shirt.usda"), str(out / "s.####.exr"),
                             "--frames", f"1:{len(names) + 2}", "--width", "640",
                             "--skip-existing", "--quiet"], capture_output=True, text=True,
                            timeout=600)
    assert resume.returncode == 0, resume.stderr
    for name, mtime in done.items():
        assert (out / name).stat().st_mtime_ns == mtime  # untouched
    assert len(whole_frames(out, 640)) == len(names) + 2
    fresh = tmp_path / "fresh"
    last = f"s.{len(names) + 2:04d}.exr"
    check = subprocess.run([sys.executable, "-m", "usdwrinkle", "render",
                            str(SAMPLES / "shirt.usda"), str(fresh / "s.####.exr"),
                            "--frames", str(len(names) + 2), "--width", "640", "--quiet"],
                           capture_output=True, text=True, timeout=600)
    assert check.returncode == 0, check.stderr
    a = oiio.ImageBuf(str(out / last)).get_pixels(oiio.FLOAT)
    b = oiio.ImageBuf(str(fresh / last)).get_pixels(oiio.FLOAT)
    finite = np.isfinite(a) & np.isfinite(b)
    assert np.array_equal(np.isfinite(a), np.isfinite(b))
    assert np.max(np.abs(a[finite] - b[finite])) <= 1e-5


def test_200_frames_through_the_writer_keep_memory_flat(gl_context, tmp_path):
    """The overlapped writer (outputs/writer.py) holds at most two frames: memory stays
    flat over a long shot, and every frame is written whole."""
    from usdwrinkle.frameloop import render_frames
    from usdwrinkle.outputs.images import layout_for
    from usdwrinkle.outputs.writer import WriteOptions
    from usdwrinkle.render.request import FrameRequest

    engine = WrinkleEngine(str(SAMPLES / "zeppelin.usda"), ctx=gl_context)
    marks = {}

    def progress(items):
        for index, item in enumerate(items):
            if index in (20, 199):
                marks[index] = rss_bytes()
            yield item

    frames = [float(f) for f in range(1, 201)]
    paths = [str(tmp_path / f"z.{int(f):04d}.png") for f in frames]
    try:
        written = render_frames(engine, FrameRequest(96, 64, 1, layout=layout_for(paths[0])),
                                WriteOptions(threads=1), frames, paths, progress=progress)
    finally:
        engine.release()
    assert written == frames
    assert marks[199] < marks[20] * 1.05, marks
    assert len(whole_frames(tmp_path, 96)) == 200


def test_a_failing_write_is_reported_and_earlier_frames_stay(tmp_path):
    """A write error on the writer thread reaches the caller; frames handed over before
    it are complete, and nothing after the in-flight window is started."""
    from usdwrinkle.outputs.writer import FrameWriter
    from usdwrinkle.process.errors import UsdWrinkleError

    started = []

    def write(path, buffers):
        started.append(path)
        if path.endswith("3"):
            raise UsdWrinkleError(f"cannot write image '{path}': disk full")
        time.sleep(0.01)
        Path(path).write_text("whole")

    with pytest.raises(UsdWrinkleError, match="disk full"):
        with FrameWriter(write, threads=1, max_in_flight=2) as writer:
            for index in range(1, 10):
                writer.submit(float(index), str(tmp_path / f"f{index}"), {})
    assert writer.written == [1.0, 2.0]
    names = {p.name for p in tmp_path.iterdir()}
    # frames in flight behind frame 3 (4, perhaps 5) are finished whole; none after them
    assert {"f1", "f2"} <= names <= {"f1", "f2", "f4", "f5"}, names
    assert all(p.read_text() == "whole" for p in tmp_path.iterdir())
    assert len(started) <= 5
