"""The paper's figures (Loviscach 2006, table 1): the one data table the bench measures
against and the report quotes."""
from __future__ import annotations

PAPER = [  # case, vertices, pixels, paper figure, unit
    ("shirt", 455, 330_000, 328.0, "fps"),
    ("zeppelin", 508, 260_000, 540.0, "fps"),
    ("curtain", 92, 505_000, 537.0, "fps"),
    ("A", 100, 1_000_000, 3.45, "ms"),
    ("B", 50_000, 55_000, 8.90, "ms"),
]


def paper_figure(case: str) -> float:
    """The paper's figure for ``case`` (fps or ms, see PAPER)."""
    return next(row[3] for row in PAPER if row[0] == case)
