"""`python -m benchmarks --quick` as a smoke test: it finishes and reports every field.

Speed is never asserted here; the figures live in docs/benchmarks.md.
"""
from __future__ import annotations

import json

import pytest

from benchmarks import main

FIELDS = {
    "paper_table": ["case", "vertices", "pixels", "pass_ms", "pass_sources", "gpu_ms", "wall_ms",
                    "wall_fps", "plain_wall_ms", "wrinkle_overhead", "paper", "paper_unit"],
    "skin_baseline": ["vertices", "usdskel_cpu_ms", "gpu_skin_ms", "gpu_skin_with_readback_ms",
                      "speedup"],
}


@pytest.mark.slow
def test_bench_quick_reports_every_field(gl_context, corpus, tmp_path):
    out_json, out_md = tmp_path / "bench.json", tmp_path / "bench.md"
    assert main(["--quick", "--json", str(out_json), "--markdown", str(out_md),
                 "--corpus", str(corpus), "--history", str(tmp_path / "none")]) == 0
    result = json.loads(out_json.read_text())
    assert result["quick"] is True
    assert {"machine", "command", "date", "paper_table", "scaling", "skin_baseline",
            "numpy_baseline", "end_to_end", "preroll", "farm", "floors", "targets",
            "paint"} <= set(result)
    assert [r["case"] for r in result["paint"]["engine"]] == ["shirt", "CesiumMan"]
    assert [r["case"] for r in result["paper_table"]] == ["shirt", "zeppelin", "curtain", "A", "B"]
    for section, keys in FIELDS.items():
        for row in result[section]:
            assert set(keys) <= set(row), (section, set(keys) - set(row))
            for key in keys:
                assert row[key] is not None
    for name in ("skin", "crush", "relax", "draw", "readback"):
        assert all(name in row["pass_ms"] for row in result["paper_table"])
    scaling = result["scaling"]
    assert len(scaling["vertices"]) >= 2 and len(scaling["pixels"]) >= 2
    assert {"slope", "intercept", "r2"} <= set(scaling["vertex_fit"])
    assert {"numpy_ms", "gpu_ms", "speedup"} <= set(result["numpy_baseline"])
    e2e = result["end_to_end"]
    for run in ("wrinkles", "no_wrinkles"):
        assert {"usd_read", "upload", "gpu", "readback", "encode", "total"} <= set(e2e[run])
    assert {"baked_2", "baked_late", "direct_late", "late_over_2", "late_frame",
            "bake_s"} <= set(result["preroll"])
    assert result["preroll"]["direct_late"] > 0 and result["preroll"]["baked_late"] > 0
    farm = result["farm"]
    assert {"frames", "serial_s", "dask_s", "serial_fps", "dask_fps", "speedup",
            "serial_cpu_utilisation", "dask_cpu_utilisation", "bake_s"} <= set(farm), farm
    assert farm["frames"] == 8 and farm["speedup"] > 0
    assert len(result["targets"]) == 13  # 7, and the paint window's 3 for each of 2 cases
    # the Storm peer and the paint window are timed by the full bench only (each starts a
    # program of its own: Blender, a Qt window)
    assert not result["peers"]["ran"] and "quick" in result["peers"]["why"]
    assert not result["paint"]["window"]["ran"]
    floors = result["floors"]
    assert {"empty_dispatch_ms", "gather6_50k_ms", "gather6_50k_tables_ms", "copy_points_ms",
            "readback_330k_rgba32f_ms"} <= set(floors)
    assert floors["copy_points"] == result["skin_baseline"][-1]["vertices"]
    text = out_md.read_text()
    nodes = result["cpu_nodes"]
    assert set(nodes["rows"]) == {"exr_serial", "exr_overlapped", "png_serial",
                                  "png_overlapped"}
    for row in nodes["rows"].values():
        assert row["fps"] > 0 and row["split_ms"]["encode"] > 0 and row["startup_s"] >= 0
    # issue 45: what a farm gets as files, and how the writer's threads scale
    written = nodes["files_written"]["rows"]
    assert [row["case"].split()[0] for row in written] == ["shirt", "shirt", "CesiumMan"]
    for row in written:
        assert row["fps"] > 0 and 0 <= row["wait_share"] < 1 and row["cpu_utilisation"] > 0
        assert 0 < row["loop_cpu_utilisation"] <= 1.05  # process_time over loop_s x cores
        assert 0 <= row["gpu_wait_share"] < 1 and row["readback_buffers"] in (1, 3)
    # writer threads against OpenEXR's own threads per file, for both stages
    combos = {(row["stage"], row["write_threads"], row["exr_threads"])
              for row in nodes["exr_threads"]["rows"]}
    assert {("shirt", 1, 0), ("CesiumMan", 1, 0)} <= combos
    assert all(row["fps"] > 0 for row in nodes["exr_threads"]["rows"])
    assert set(nodes["encoding"]["threads"][".exr"]) >= {"1"}
    assert set(nodes["encoding"]["compressions"]) == {"zip", "zips", "piz", "dwaa", "none"}
    tri = result["triangulation"]
    assert tri["polygon"]["triangles"] == 10_000 - 2 and tri["polygon"]["ms"] > 0
    assert tri["quads"]["triangles"] == 2 * tri["quads"]["faces"] and tri["quads"]["ms"] > 0
    for heading in ("## Targets", "## The paper's table", "## Scaling", "## Baselines",
                    "## End to end", "## What the rasteriser costs by itself", "## Farms",
                    "## Triangulation of hostile meshes", "## CPU render nodes",
                    "### Encoding on every core", "### Files written",
                    "### Writer threads and OpenEXR's threads"):
        assert heading in text
    assert result["machine"]["gl_renderer"] in text


def test_quick_never_writes_the_committed_report(monkeypatch):
    """Issue 27: bench --quick overwrote docs/benchmarks.md with smoke-test figures; its
    default report is bench-quick.md in the current folder (the full bench's stays)."""
    import benchmarks

    seen = []
    monkeypatch.setattr(benchmarks, "run", lambda args: seen.append(args.markdown) or 0)
    for argv in (["--quick"], [], ["--quick", "--markdown", "x.md"]):
        assert benchmarks.main(argv) == 0
    assert seen == ["bench-quick.md", "docs/benchmarks.md", "x.md"]


def test_usdwrinkle_bench_runs_the_checkouts_benchmarks(tmp_path):
    """Issue 25: the installed CLI imports nothing of benchmarks/; `usdwrinkle bench ARGS`
    runs `python -m benchmarks ARGS` in a child process. --from-json measures nothing, so
    the child's report is the committed run's, rewritten."""
    import subprocess
    import sys
    from pathlib import Path

    checkout = Path(__file__).resolve().parents[1]
    out = tmp_path / "report.md"
    done = subprocess.run(
        [sys.executable, "-m", "usdwrinkle", "bench", "--from-json",
         str(checkout / "docs" / "benchmarks.json"), "--markdown", str(out),
         "--history", str(tmp_path / "none")],
        cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    saved = json.loads((checkout / "docs" / "benchmarks.json").read_text())
    text = out.read_text()
    assert saved["machine"]["gl_renderer"] in text and "## The paper's table" in text
    bad = subprocess.run([sys.executable, "-m", "usdwrinkle", "bench", "--no-such-option"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "--no-such-option" in bad.stderr


def test_from_json_on_a_file_that_is_no_saved_run_is_one_line(tmp_path, capsys):
    """Issue 42, finding 13: bench --from-json on garbage printed a traceback."""
    garbage, other = tmp_path / "g.json", tmp_path / "o.json"
    garbage.write_text("garbage")
    other.write_text('{"a": 1}')
    for path, said in ((garbage, "is not JSON"), (other, "is not a saved run"),
                       (tmp_path / "missing.json", "cannot read --from-json")):
        assert main(["--from-json", str(path), "--markdown", str(tmp_path / "x.md")]) == 2
        err = capsys.readouterr().err
        assert said in err and "Traceback" not in err and len(err.splitlines()) == 1
    assert not (tmp_path / "x.md").exists()


def test_the_committed_report_is_its_json_s(tmp_path):
    """docs/benchmarks.md is the output of its command: rewritten from docs/benchmarks.json
    it is the same file."""
    from pathlib import Path

    docs = Path(__file__).resolve().parents[1] / "docs"
    out = tmp_path / "b.md"
    assert main(["--from-json", str(docs / "benchmarks.json"), "--markdown", str(out),
                 "--history", str(docs / "bench")]) == 0
    assert out.read_text() == (docs / "benchmarks.md").read_text()
