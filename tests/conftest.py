"""Shared fixtures: one GL context per session, the corpus folder, small meshes."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

import usdwrinkle  # noqa: F401  (registers the schema before any other USD use)
from usdwrinkle.authoring.builders import grid_sheet  # noqa: F401  (the tests' sheets)

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
