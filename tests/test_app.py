"""The application layer (issue 44): one job per kind of work, and the doors (the command
line, the Python API, the farm, usdview's plugin) adapters onto it."""
from __future__ import annotations

import logging
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Usd

from usdwrinkle import api, usdview
from usdwrinkle.app.options import BakeOptions, RenderOptions, ShotOptions
from usdwrinkle.app.render import RenderJob
from usdwrinkle.app.shot import Shot
from usdwrinkle.cli.flags import flagged
from usdwrinkle.cli.main import main
from usdwrinkle.process import log
from usdwrinkle.process.errors import UsdWrinkleError

SHIRT = str(Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda")
POLICY = "a render policy added to the job alone"


@pytest.fixture
def new_policy(monkeypatch):
    """A new warning added where render policy lives, RenderJob.mesh_notes, and nowhere
    else."""
    said = RenderJob.mesh_notes

    def mesh_notes(self, stage, wrinkled):
        return [*said(self, stage, wrinkled), POLICY]

    monkeypatch.setattr(RenderJob, "mesh_notes", mesh_notes)


def test_a_render_policy_reaches_every_door(gl_context, tmp_path, capfd, caplog, new_policy):
    """The warning shows in the command line's stderr, in the API's collected warnings,
    in the farm client's (it checks before it reaches a scheduler, here one it refuses)
    and in the host's logging under usdview (whose status line reports the outcome)."""
    assert main(["render", SHIRT, str(tmp_path / "cli.png"), "--frames", "24",
                 "--width", "32", "--quiet"]) == 0
    assert f"usdwrinkle: warning: {POLICY}" in capfd.readouterr().err
    with log.collect() as messages:
        api.render(SHIRT, tmp_path / "api.png", frames=[24], width=32)
    assert POLICY in messages
    with log.collect() as messages, pytest.raises(UsdWrinkleError, match="protocol"):
        api.render(SHIRT, tmp_path / "farm.####.png", frames="23:24", width=32,
                   dask="ucx://nowhere:1")
    assert POLICY in messages
    stage = Usd.Stage.Open(SHIRT)
    status: list[str] = []
    viewer = SimpleNamespace(stage=stage, frame=Usd.TimeCode(24), selectedPrims=[],
                             prim=None, cameraPrim=None, PrintStatus=status.append)
    with caplog.at_level(logging.WARNING, logger="usdwrinkle"):
        paths = usdview.render_current_frame(viewer, outdir=str(tmp_path),
                                             opener=lambda path: None, width=32,
                                             ctx=gl_context)
    assert len(paths) == 2 and "rendered" in status[-1]
    assert any(record.getMessage() == POLICY for record in caplog.records)


def test_the_job_renders_what_the_command_renders(gl_context, tmp_path):
    """RenderJob from Python, with composition options, against the command line."""
    shot = Shot(SHIRT, ShotOptions(relax_iterations=4))
    result = RenderJob(shot, tmp_path / "job.####.png", "23:24",
                       RenderOptions(width=48, samples=1)).run(gl_context)
    assert result.frames == [23.0, 24.0] and result.written == [23.0, 24.0]
    assert (result.width, result.height) == (48, 32) and result.skipped == 0
    assert main(["render", SHIRT, str(tmp_path / "cli.####.png"), "--frames", "23:24",
                 "--width", "48", "--samples", "1", "--relax-iterations", "4",
                 "--quiet"]) == 0
    for frame in ("0023", "0024"):
        ours = oiio.ImageBuf(str(tmp_path / f"job.{frame}.png")).get_pixels(oiio.UINT8)
        theirs = oiio.ImageBuf(str(tmp_path / f"cli.{frame}.png")).get_pixels(oiio.UINT8)
        np.testing.assert_array_equal(ours, theirs)


@pytest.mark.parametrize("make,field", [
    (lambda: RenderOptions(width="wide"), "width"),
    (lambda: RenderOptions(samples=2.5), "samples"),
    (lambda: RenderOptions(shade_samples=1), "shade_samples"),
    (lambda: RenderOptions(exr_compression="zstd"), "exr_compression"),
    (lambda: ShotOptions(sublayer=[3]), "sublayer"),
    (lambda: BakeOptions(tangent_space="mikk"), "tangent_space"),
    (lambda: BakeOptions(levels=True), "levels"),
])
def test_a_bad_option_names_its_field(make, field):
    with pytest.raises(UsdWrinkleError) as caught:
        make()
    assert f"`{field}`" in str(caught.value)


def test_range_errors_name_fields_for_python_and_flags_for_the_command_line(tmp_path,
                                                                            capfd):
    with pytest.raises(UsdWrinkleError, match="`relax_iterations` must be in 0..10,000"):
        api.render(SHIRT, tmp_path / "x.png", relax_iterations=-1)
    with pytest.raises(UsdWrinkleError, match="`map_size`, `uv` need `maps`"):
        api.bake(SHIRT, tmp_path / "x.usda", map_size=64, uv="st")
    assert main(["bake", SHIRT, str(tmp_path / "x.usda"), "--map-size", "64", "--uv",
                 "st"]) == 2
    assert "usdwrinkle: error: --map-size, --uv need --maps" in capfd.readouterr().err
    assert main(["render", SHIRT, str(tmp_path / "x.png"), "--relax-iterations",
                 "-1"]) == 2
    assert "error: --relax-iterations must be in 0..10,000" in capfd.readouterr().err
    assert not list(tmp_path.iterdir())


def test_flags_replace_backquoted_fields_only():
    assert flagged("`exr_half` and `map_size` (/World/width)") == \
        "--exr-half and --map-size (/World/width)"
    assert flagged("width `width`") == "width --width"


def test_writer_threads_follow_the_cores_and_the_memory(monkeypatch):
    """Issue 45: the writer used 1 thread and 2 frames in flight on any node."""
    from usdwrinkle.outputs import writer
    from usdwrinkle.process import memory

    monkeypatch.setattr(writer, "cores", lambda: 16)
    assert writer.default_threads() == 15
    monkeypatch.setattr(writer, "cores", lambda: 2)
    assert writer.default_threads() == 1
    monkeypatch.setattr(writer, "cores", lambda: 1)
    assert writer.default_threads() == 1
    monkeypatch.setattr(memory, "available_memory", lambda: 64 * 2**30)
    assert writer.frames_in_flight(15, 66 * 2**20) == 16  # 1080p EXR: 16 x 66 MB fit
    monkeypatch.setattr(memory, "available_memory", lambda: 1 * 2**30)
    assert writer.frames_in_flight(15, 66 * 2**20) == 3   # a quarter of 1 GiB holds 3
    assert writer.frames_in_flight(15, 2**30) == 2        # never fewer than 2
    monkeypatch.setattr(memory, "available_memory", lambda: None)
    assert writer.frames_in_flight(7, 2**30) == 8


def test_a_job_resolves_its_writer_threads(monkeypatch):
    from usdwrinkle.outputs import writer

    monkeypatch.setattr(writer, "cores", lambda: 16)
    job = RenderJob(Shot(SHIRT), "x.####.png")
    assert job.write_options(1920, 1080).threads == 15
    assert job.write_options(1920, 1080, chunked=True).threads == 1
    assert RenderJob(Shot(SHIRT), "x.####.png", options=RenderOptions(write_threads=3)) \
        .write_options(64, 64, chunked=True).threads == 3
    with pytest.raises(UsdWrinkleError, match="`write_threads` must be in 0..64"):
        RenderOptions(write_threads=65).check()


def test_exr_files_share_the_cores_with_openexrs_threads(monkeypatch):
    """Issue 45: on a 16-core H200 node, 24 shirt frames at 1080p EXR ran at 19.0 fps with
    15 writer threads compressing each file alone, 26.0 with 4 writer threads of 4
    OpenEXR threads each (benchmarks/exr_threads.py, docs/benchmarks-gpu.md)."""
    from usdwrinkle.outputs import writer

    monkeypatch.delenv("USDWRINKLE_EXR_THREADS", raising=False)
    expected = {16: (4, 4), 8: (4, 2), 4: (3, 1), 2: (1, 1), 1: (1, 0)}
    for cores, (threads, per_file) in expected.items():
        monkeypatch.setattr(writer, "cores", lambda cores=cores: cores)
        image = RenderJob(Shot(SHIRT), "x.####.exr").write_options(1920, 1080)
        assert (image.threads, image.exr_threads) == (threads, per_file), cores
        png = RenderJob(Shot(SHIRT), "x.####.png").write_options(1920, 1080)
        assert png.threads == max(1, cores - 1)
        chunk = RenderJob(Shot(SHIRT), "x.####.exr").write_options(64, 64, chunked=True)
        assert (chunk.threads, chunk.exr_threads) == (1, 0)  # one worker per core
    monkeypatch.setenv("USDWRINKLE_EXR_THREADS", "8")
    assert RenderJob(Shot(SHIRT), "x.####.exr").write_options(64, 64).exr_threads == 8
    monkeypatch.setenv("USDWRINKLE_EXR_THREADS", "many")
    with pytest.raises(UsdWrinkleError, match="USDWRINKLE_EXR_THREADS must be in 0..64"):
        RenderJob(Shot(SHIRT), "x.####.exr").write_options(64, 64)
