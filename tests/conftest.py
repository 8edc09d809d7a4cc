"""Shared fixtures: one GL context per session, the corpus folder, small meshes."""
from __future__ import annotations

import os
import shutil
import subprocess
import time
from pathlib import Path

import pytest

import usdwrinkle  # noqa: F401  (registers the schema before any other USD use)
from usdwrinkle.authoring.builders import grid_sheet  # noqa: F401  (the tests' sheets)

REPO = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("USDWRINKLE_CORPUS", REPO.parent / "shared" / "corpus"))


def pytest_configure(config):
    """The user's files (brush presets, recent stages: app/presets.py) go to a folder of
    this run's own, in this process and every process it starts, never ~/.config."""
    import tempfile

    if "USDWRINKLE_CONFIG_DIR" not in os.environ:
        os.environ["USDWRINKLE_CONFIG_DIR"] = tempfile.mkdtemp(prefix="usdwrinkle-config-")


def pytest_addoption(parser):
    parser.addoption("--regenerate-goldens", action="store_true",
                     help="rewrite tests/goldens/*.exr from the current renderer")
    parser.addoption("--require-realclients", action="store_true",
                     help="fail, instead of skip, the real-client tier (Storm, Cycles) "
                          "where no Python with Blender's bpy is found (also "
                          "USDWRINKLE_REQUIRE_REALCLIENTS=1, which .ci/run sets)")


#: why the real-client tier cannot run here (None: it can); found once per session
_REALCLIENT = {}


def realclient_problem() -> str | None:
    if "problem" not in _REALCLIENT:
        import sys

        sys.path.insert(0, str(REPO))
        from realclients import NoClient, bpy_python

        try:
            _REALCLIENT["python"] = bpy_python()
            _REALCLIENT["problem"] = None
        except NoClient as exc:
            _REALCLIENT["problem"] = str(exc)
    return _REALCLIENT["problem"]


@pytest.fixture(scope="session")
def realclient(request, gl_context):
    """The real-client tier (marker ``realclient``): skipped, saying why, where no Python
    with bpy is found; an error with --require-realclients."""
    problem = realclient_problem()
    if problem is not None:
        if request.config.getoption("--require-realclients") or \
                os.environ.get("USDWRINKLE_REQUIRE_REALCLIENTS") == "1":
            pytest.fail(f"the real-client tier cannot run: {problem}")
        pytest.skip(f"real-client tier not run: {problem}")
    return _REALCLIENT["python"]


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    """Say so, at the end of every run, when the real-client tier did not run."""
    skipped = [report for report in terminalreporter.stats.get("skipped", [])
               if "real-client tier not run" in str(report.longrepr)]
    if skipped:
        terminalreporter.write_line(
            f"REAL-CLIENT TIER NOT RUN ({len(skipped)} tests): {realclient_problem()}",
            yellow=True, bold=True)
    paint = [report for report in terminalreporter.stats.get("skipped", [])
             if "paint-window tier not run" in str(report.longrepr)]
    if paint:
        reason = str(paint[0].longrepr).split("paint-window tier not run: ")[-1].rstrip("')")
        terminalreporter.write_line(f"PAINT-WINDOW TIER NOT RUN ({len(paint)} tests): {reason}",
                                    yellow=True, bold=True)
    if corpus_problem():
        terminalreporter.write_line(f"CORPUS MISSING: {corpus_problem()}", red=True, bold=True)


@pytest.fixture(scope="session")
def gl_context():
    from usdwrinkle.render.context import create_context
    return create_context()


#: what the tests read from the corpus, and where each comes from
CORPUS_SOURCES = (
    ("openusd-usdskel/", "lbs.usda, dqs.usda, blendshapes.usda, blendshapesWithNormals.usda "
     "and baseline/*.baked.usda from OpenUSD's pxr/usd/usdSkel/testenv/"
     "testUsdSkelBakeSkinning; twoBends.usda, arm.usda and test_lbs.usda from "
     "pxr/usdImaging/usdImagingGL/testenv (github.com/PixarAnimationStudios/OpenUSD)"),
    ("usd-wg/", "CesiumMan.usdz, RiggedFigure.usdz, RiggedSimple.usdz and "
     "SoC-ElephantWithMonochord.usdc from the USD working group's assets "
     "(github.com/usd-wg/assets)"),
)


def corpus_problem() -> str | None:
    """Why the corpus tests cannot run here (None: they can), saying what to get."""
    missing = [folder for folder, _ in CORPUS_SOURCES if not (CORPUS / folder).is_dir()]
    if not missing:
        return None
    wanted = "; ".join(f"{folder}: {what}" for folder, what in CORPUS_SOURCES
                       if folder in missing)
    return (f"the shared test corpus is missing at {CORPUS} ({', '.join(missing)}); set "
            f"USDWRINKLE_CORPUS to a folder that holds {wanted}")


@pytest.fixture(scope="session")
def corpus() -> Path:
    problem = corpus_problem()
    if problem:
        pytest.fail(problem)
    return CORPUS


@pytest.fixture
def regenerate_goldens(request) -> bool:
    return request.config.getoption("--regenerate-goldens")


def paint_problem() -> str | None:
    """Why the paint-window tier cannot run here (None: it can)."""
    missing = [tool for tool in ("Xvfb", "xdotool") if shutil.which(tool) is None]
    if missing:
        return (f"{' and '.join(missing)} not found (apt-get install xvfb xdotool "
                "libxcb-icccm4 libxcb-keysyms1)")
    try:
        import PySide6  # noqa: F401
    except ImportError:
        return "PySide6 is not installed (pip install -e '.[test]')"
    return None


@pytest.fixture(scope="module")
def display():
    """An X server of this module's own: its DISPLAY."""
    problem = paint_problem()
    if problem is not None:
        if os.environ.get("USDWRINKLE_REQUIRE_PAINT") == "1":
            pytest.fail(f"the paint-window tier cannot run: {problem}")
        pytest.skip(f"paint-window tier not run: {problem}")
    read, write = os.pipe()
    server = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0",
                               "1600x1000x24", "-nolisten", "tcp"], pass_fds=(write,),
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write)
    number = b""
    deadline = time.monotonic() + 30
    while not number.endswith(b"\n") and time.monotonic() < deadline:
        chunk = os.read(read, 16)
        if not chunk:
            break
        number += chunk
    os.close(read)
    if not number.strip():
        server.kill()
        pytest.fail("Xvfb did not start")
    yield f":{number.decode().strip()}"
    server.terminate()
    server.wait(10)
