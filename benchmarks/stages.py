"""Where the bench finds its stages: the bundled samples, the shared corpus, and the
synthetic sleeve (usdwrinkle.authoring.builders, shared with the tests)."""
from __future__ import annotations

import os
from pathlib import Path

from usdwrinkle.authoring.builders import sleeve_stage  # noqa: F401  (re-exported)


def default_corpus() -> Path | None:
    env = os.environ.get("USDWRINKLE_CORPUS")
    if env:
        return Path(env)
    candidate = Path(__file__).resolve().parents[2] / "shared" / "corpus"
    return candidate if candidate.is_dir() else None

