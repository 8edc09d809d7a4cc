"""The length pass against the converged referee: every bar of a shot with and without it
(docs/method.md, "The cloth's length"; docs/physics.md, "The cloth's length").

    python -m benchmarks.physics.length [--write docs/physics.md] [--only SHOT ...]
                                        [--grid M] [--cache .physics-cache]

Per shot of the converged sweep, on the run the converged table judges it on (1 cm for
the curtains, the panels and the 5 cm sleeve, 2 cm for the others; --grid M: every shot
at M instead; 2 cm for all until 2026-12-07) and 160 iterations, as the converged table
measures it (referee.sweep_row: matched W, the simulation's pinned points marked
wrinkle:held), once with the length pass turned off
(contract.LENGTH_LAW 0, the law before 2026-12-06) and once as usdwrinkle draws: the
heights over the phases (ours / the cloth's), the amplitude-field correlation, our area
over the rest area where compressed beside the cloth's own, and on the sleeves the crest
motion (ours / the cloth's, bending and held). A shot not in the cache is simulated first
(10-30 minutes of solver at 2 cm on one core, 20-55 at 1 cm).
"""
from __future__ import annotations

from ..blocks import markers
from . import referee

NAME = "referee-length"


def _bars(sim, fine) -> dict:
    row = referee.sweep_row(sim, fine)
    heights = [h for _, h in row["matched"].values()]  # per_phase of the matched bake
    return {"width": row["width"], "heights": (min(heights), max(heights)),
            "correlation": row["correlation"], "area": row["area"],
            "sim area": row["sim_area"], "motion": row["motion"]}


def shot_rows(name: str, cache, grid: float | None) -> dict:
    """The shot's bars without the length pass ("off") and with it ("on")."""
    from usdwrinkle.render import bindings

    grid = referee.referee_grid(name, True) if grid is None else grid
    sim, fine = referee.referee_pair(name, cache, grid, referee.CONVERGED[1])
    law = bindings.COMMON["LENGTH_LAW"]
    out = {"grid": grid}
    try:
        for key, value in (("off", "0"), ("on", law)):
            bindings.COMMON["LENGTH_LAW"] = value
            out[key] = _bars(sim, fine)
    finally:
        bindings.COMMON["LENGTH_LAW"] = law
    return out


def report(rows: dict, seconds: float, grid: float | None) -> str:
    end = markers(NAME)[1]
    lines = referee.shot_block_head(NAME, "length", seconds, grid) + [
        "Per shot at its matched W (as the converged table bakes it), without the length "
        "pass and with it: heights over the phases (ours / the cloth's), the amplitude-field "
        "correlation, our area over the rest area where compressed (the cloth's own beside "
        "it), and on the sleeves the crest motion (ours / the cloth's, bending and held). "
        "Bars: heights within 1.25x, correlation >= 0.85 (0.75 shear), area in [0.95, 1.05], "
        "motion <= 1.5x.", "",
        "| shot | grid | matched W: off, on | without | with |", "|---|---|---|---|---|"]

    def cell(b):
        low, high = b["heights"]
        motion = "".join(f", {key} {value:.2f}x" for key, value in b["motion"].items())
        return (f"{low:.2f}-{high:.2f}x, {b['correlation']:.3f}, {b['area']:.3f} "
                f"(cloth {b['sim area']:.3f}){motion}")

    for name, row in rows.items():
        lines.append(f"| {name} | {row['grid'] * 100:g} cm | {row['off']['width'] * 100:.1f}, "
                     f"{row['on']['width'] * 100:.1f} cm | {cell(row['off'])} | "
                     f"{cell(row['on'])} |")
    lines += ["", end]
    return "\n".join(lines)


def main(argv=None) -> int:
    return referee.shot_block_main(argv, "length", NAME, __doc__, shot_rows, report,
                                   shots=tuple(referee.SWEEP), grid=None,
                                   grid_doc="each shot's judged grid")


if __name__ == "__main__":
    raise SystemExit(main())
