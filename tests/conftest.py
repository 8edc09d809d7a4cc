"""Shared fixtures: one GL context per session, the corpus folder, small meshes."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import usdwrinkle  # noqa: F401  (registers the schema before any other USD use)

REPO = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("USDWRINKLE_CORPUS", REPO.parent / "shared" / "corpus"))


def pytest_addoption(parser):
    parser.addoption("--regenerate-goldens", action="store_true",
                     help="rewrite tests/goldens/*.exr from the current renderer")


@pytest.fixture(scope="session")
def gl_context():
    from usdwrinkle.render.context import create_context
    return create_context()


@pytest.fixture(scope="session")
def corpus() -> Path:
    if not CORPUS.is_dir():
        pytest.fail(f"the shared corpus is missing at {CORPUS} (set USDWRINKLE_CORPUS)")
    return CORPUS


@pytest.fixture
def regenerate_goldens(request) -> bool:
    return request.config.getoption("--regenerate-goldens")


def grid_sheet(nx: int = 21, ny: int = 21, size: float = 2.0):
    """A flat sheet in the XY plane: points (n,3), faceVertexCounts, faceVertexIndices."""
    xs = np.linspace(-size / 2, size / 2, nx)
    ys = np.linspace(-size / 2, size / 2, ny)
    gx, gy = np.meshgrid(xs, ys)
    points = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], 1).astype(np.float32)
    quads = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a = j * nx + i
            quads.append([a, a + 1, a + nx + 1, a + nx])
    quads = np.array(quads, np.int32)
    return points, np.full(len(quads), 4, np.int32), quads.ravel()
