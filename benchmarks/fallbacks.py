"""The product's fallbacks set in this process for a measurement, and restored after
(benchmarks.physics.candidate's candidates, benchmarks.stability's --slack draws): what a
stage that authors none of them reads, without changing the code."""
from __future__ import annotations

import contextlib


@contextlib.contextmanager
def fallbacks(settings: dict):
    """The fallbacks ``settings`` names set in this process (restored after): its keys
    slack, irregularity, widths ({cloth: metres}), tube (metres), gate ((low, high));
    a key left out keeps the code's value."""
    from usdwrinkle.method import contract, folds
    from usdwrinkle.usd import schema

    saved = (schema.DEFAULT_SLACK, schema.DEFAULT_IRREGULARITY, dict(schema.CLOTH_WIDTHS_M),
             schema.CURVED_WIDTH_M, contract.CURVED_COARSENING, folds.CURVED_COARSENING)
    try:
        schema.DEFAULT_SLACK = settings.get("slack", schema.DEFAULT_SLACK)
        schema.DEFAULT_IRREGULARITY = settings.get("irregularity", schema.DEFAULT_IRREGULARITY)
        schema.CLOTH_WIDTHS_M.update(settings.get("widths", {}))
        schema.CURVED_WIDTH_M = settings.get("tube", schema.CURVED_WIDTH_M)
        if "gate" in settings:
            gate = (*settings["gate"], *contract.CURVED_COARSENING[2:])
            contract.CURVED_COARSENING = folds.CURVED_COARSENING = gate
        yield
    finally:
        (schema.DEFAULT_SLACK, schema.DEFAULT_IRREGULARITY, widths, schema.CURVED_WIDTH_M,
         contract.CURVED_COARSENING, folds.CURVED_COARSENING) = saved
        schema.CLOTH_WIDTHS_M.clear()
        schema.CLOTH_WIDTHS_M.update(widths)
