"""Farms: the chunk recipe of OpenCue/Deadline, and render --dask on a local cluster and on
a real 'dask scheduler' with 'dask worker' processes (one of them killed mid-run)."""
from __future__ import annotations

import os
import random
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from usdwrinkle.cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
SHIRT = str(SAMPLES / "shirt.usda")


def cli(*args, timeout=600, **kwargs):
    return subprocess.run([sys.executable, "-m", "usdwrinkle", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, **kwargs)


def pixels(path):
    buf = oiio.ImageBuf(str(path))
    data = buf.get_pixels(oiio.FLOAT)
    assert data is not None, path
    return data


def assert_identical_frames(a: Path, b: Path, pattern="s.*.exr", count=None):
    names = sorted(p.name for p in a.glob(pattern))
    assert names == sorted(p.name for p in b.glob(pattern))
    if count is not None:
        assert len(names) == count
    for name in names:
        assert np.array_equal(pixels(a / name).view(np.uint32), pixels(b / name).view(np.uint32)), \
            name


def no_temporaries(folder: Path):
    hidden = [p.name for p in folder.iterdir() if p.name.startswith(".")]
    assert not hidden, hidden


def test_chunk_recipe_in_shuffled_processes_equals_a_serial_render(gl_context, tmp_path):
    """README, 'Rendering on a farm': bake once, then one command per chunk."""
    layer = tmp_path / "shot_wrinkles.usdc"
    assert cli("bake", SHIRT, layer, "--quiet").returncode == 0
    chunks = [(start, min(start + 4, 24)) for start in range(1, 25, 5)]
    random.Random(3).shuffle(chunks)
    farm = tmp_path / "farm"
    for start, end in chunks:  # each chunk its own process, as a farm task
        done = cli("render", layer, farm / "s.####.exr", "--frames", f"{start}:{end}",
                   "--width", "160", "--quiet")
        assert done.returncode == 0, done.stderr
    serial = tmp_path / "serial"
    assert main(["render", str(layer), str(serial / "s.####.exr"), "--width", "160",
                 "--quiet"]) == 0
    assert_identical_frames(farm, serial, count=24)
    no_temporaries(farm)


def test_dask_local_cluster_equals_a_serial_render_from_the_same_bake(gl_context, tmp_path):
    out = tmp_path / "dask"
    scratch = tmp_path / "tmpdir"
    scratch.mkdir()
    done = cli("render", SHIRT, out / "s.####.exr", "--dask", "--workers", "2",
               "--width", "160", env={**os.environ, "TMPDIR": str(scratch)})
    assert done.returncode == 0, done.stderr
    assert not list(scratch.iterdir())  # no dask-scratch-space left behind (issue 42)
    layer = out / "usdwrinkle_bake" / "shirt.wrinkles.usdc"
    assert len(list(out.glob("*"))) == 24 + 1   # the frames, and the bake's folder
    assert f"baked wave fields to {layer}" in done.stderr
    assert "wrote 24 frame(s)" in done.stderr and "fps over the whole run" in done.stderr
    assert "baked wave fields: /World/Arm/Sleeve" in done.stderr
    assert done.stdout == ""  # what a run says is on stderr, with its progress
    # the log starts as a serial render's does: version, stage and GL (issue 54)
    from usdwrinkle import __version__

    first = done.stderr.splitlines()[0]
    assert first.startswith(f"usdwrinkle: version {__version__}, render on Dask {SHIRT}, "
                            "GL renderer "), first
    serial = tmp_path / "serial"
    assert main(["render", str(layer), str(serial / "s.####.exr"), "--width", "160",
                 "--quiet"]) == 0
    assert_identical_frames(out, serial, count=24)
    no_temporaries(out)
    # a stage that holds its bake is not baked again
    again = cli("render", layer, tmp_path / "again" / "s.####.exr", "--dask", "--workers",
                "2", "--width", "160", "--frames", "20:24")
    assert again.returncode == 0, again.stderr
    assert "baked wave fields to" not in again.stderr
    assert_identical_frames(tmp_path / "again", serial, pattern="s.002[0-4].exr", count=5)


@pytest.mark.slow
def test_dask_renders_cesium_man_48_frames(gl_context, corpus, tmp_path):
    stage = corpus / "usd-wg" / "CesiumMan.usdz"
    out = tmp_path / "dask"
    done = cli("render", stage, out / "c.####.exr", "--all-meshes", "--dask", "--workers", "2",
               "--width", "96", "--quiet")
    assert done.returncode == 0, done.stderr
    serial = tmp_path / "serial"
    layer = out / "usdwrinkle_bake" / "CesiumMan.wrinkles.usdc"
    assert main(["render", str(layer), str(serial / "c.####.exr"), "--all-meshes", "--width",
                 "96", "--quiet"]) == 0
    assert_identical_frames(out, serial, pattern="c.*.exr", count=48)


def test_an_input_error_is_reported_once(gl_context, tmp_path):
    done = cli("render", SHIRT, tmp_path / "s.####.png", "--dask", "--workers", "2",
               "--camera", "nope")
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("usdwrinkle: error: camera 'nope'"), lines


def test_an_error_inside_a_chunk_is_reported_once(gl_context, tmp_path):
    from helpers import SLEEVE, edited_copy, set_sample

    layer = tmp_path / "bake.usda"
    assert main(["bake", SHIRT, str(layer), "--quiet"]) == 0
    broken = edited_copy(layer, tmp_path / "broken.usda", set_sample(
        "phase", 10, lambda v: np.full_like(v, np.nan)))
    out = tmp_path / "frames"
    done = cli("render", broken, out / "s.####.png", "--dask", "--workers", "2", "--chunk",
               "3", "--width", "64", "--quiet")
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "usdwrinkle: error: baked field is not finite (NaN or Inf) "
        f"({SLEEVE}.primvars:wrinkle:phase at frame 10)"]
    no_temporaries(out)


def test_without_dask_the_option_says_so(gl_context, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if not installed
    assert main(["render", SHIRT, str(tmp_path / "s.####.png"), "--dask"]) == 2
    assert capsys.readouterr().err.strip() == (
        "usdwrinkle: error: --dask needs Dask's distributed scheduler: "
        "pip install 'usdwrinkle[farm]'")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_remote_scheduler_survives_a_killed_worker(gl_context, tmp_path):
    """A real 'dask scheduler' and two 'dask worker' processes on 127.0.0.1; one worker
    is killed mid-run. Every frame is written whole, and none twice."""
    from distributed import Client

    layer = tmp_path / "bake.usdc"
    assert main(["bake", SHIRT, str(layer), "--quiet"]) == 0
    address = f"tcp://127.0.0.1:{_free_port()}"
    dask = [sys.executable, "-m", "dask"]
    logs = open(tmp_path / "dask.log", "w")  # noqa: SIM115 - closed in finally
    procs = [subprocess.Popen([*dask, "scheduler", "--host", "127.0.0.1", "--port",
                               address.rsplit(":", 1)[1], "--no-dashboard"],
                              stdout=logs, stderr=logs)]
    try:
        workers = [subprocess.Popen([*dask, "worker", address, "--nthreads", "1", "--no-nanny",
                                     "--no-dashboard", "--name", f"w{i}"],
                                    stdout=logs, stderr=logs) for i in range(2)]
        procs += workers
        with Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=120)
        out = tmp_path / "frames"
        render = subprocess.Popen(
            [sys.executable, "-m", "usdwrinkle", "render", str(layer), str(out / "s.####.exr"),
             "--dask", address, "--chunk", "3", "--width", "480"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        procs.append(render)
        deadline = time.time() + 300
        while time.time() < deadline and len(list(out.glob("s.*.exr"))) < 4:
            time.sleep(0.02)
        workers[0].kill()  # SIGKILL: no chance to clean up
        before = {p.name: p.stat().st_ino for p in out.glob("s.*.exr")}
        _, err = render.communicate(timeout=300)
        assert render.returncode == 0, err
        # the frames a dead worker's attempt wrote count as written (the summary said
        # "kept 6 complete frame(s) (--skip-existing)" without that flag)
        assert "wrote 24 frame(s)" in err and "--skip-existing" not in err, err
        names = sorted(p.name for p in out.glob("s.*.exr"))
        assert names == [f"s.{f:04d}.exr" for f in range(1, 25)]
        for name in names:
            assert pixels(out / name).shape[:2] == (320, 480), name  # whole
        for name, inode in before.items():  # not written again after the kill
            assert (out / name).stat().st_ino == inode, name
        no_temporaries(out)
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
            proc.wait(timeout=30)
        logs.close()


@pytest.mark.slow
def test_ctrl_c_stops_the_cluster_and_leaves_no_temporary(gl_context, tmp_path):
    import psutil

    out = tmp_path / "frames"
    proc = subprocess.Popen(
        [sys.executable, "-m", "usdwrinkle", "render", SHIRT, str(out / "s.####.exr"),
         "--frames", "1:200", "--dask", "--workers", "2", "--width", "480", "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.time() + 300
        while time.time() < deadline and len(list(out.glob("s.*.exr"))) < 3:
            time.sleep(0.02)
        children = psutil.Process(proc.pid).children(recursive=True)
        assert children  # the local cluster's processes
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    gone, alive = psutil.wait_procs(children, timeout=30)
    assert not alive, alive
    no_temporaries(out)
    for path in out.glob("s.*.exr"):
        assert pixels(path).shape[:2] == (320, 480)
    assert 3 <= len(list(out.glob("s.*.exr"))) < 200
    assert not os.path.exists(out / ".tmp")
