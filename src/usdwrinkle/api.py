"""usdwrinkle from Python: render and bake a shot in-process, with the command line's
options as keyword arguments.

    from usdwrinkle import api

    frames = api.render("shot.usda", "out/shot.####.exr", frames="1:24", width=960)
    layer = api.bake("shot.usda", "shot_wrinkles.usdc", maps="normal", with_points=True)

Each call runs the same code as ``usdwrinkle render`` or ``usdwrinkle bake``, with the
same checks and defaults (``usdwrinkle render --help`` lists every option). A keyword is
the option's long name with ``_`` for ``-``: ``no_wrinkles=True``, ``all_meshes=True``,
``skip_existing=True``, ``dask="local"``. ``frames`` takes the command line's text
("1:24", "1,5,9", "1:24x2") or a list of numbers. A problem with the input raises
:class:`usdwrinkle.errors.UsdWrinkleError` with the command line's one-line message.
Warnings go through the ``usdwrinkle`` logger (usdwrinkle/log.py): on stderr as
``usdwrinkle: warning: ...`` unless the caller collects them
(``with usdwrinkle.log.collect() as messages: api.render(...)``) or silences them.
``quiet`` (True by default here) leaves out the progress bars and the closing line.
``usdwrinkle.api.UsdWrinkleError`` is the error type.

Authoring is :class:`usdwrinkle.WrinkleAPI` (and ``usdwrinkle apply`` on the command
line).
"""
from __future__ import annotations

import argparse

from .errors import UsdWrinkleError

__all__ = ["UsdWrinkleError", "bake", "render"]


def _namespace(command: str, stage, output, frames, options: dict) -> argparse.Namespace:
    """The command's parsed options: its parser's defaults, then ``options``."""
    from .cli.main import build_parser

    args = build_parser().parse_args([command, str(stage), str(output)])
    known = set(vars(args)) - {"command", "run", "stage", "output", "frames", "debug"}
    unknown = sorted(set(options) - known)
    if unknown:
        raise TypeError(f"usdwrinkle.api.{command}() got unknown option(s) "
                        f"{', '.join(unknown)}; it takes {', '.join(sorted(known))}")
    if frames is not None and not isinstance(frames, str):
        frames = ",".join(repr(float(f)) for f in frames)
    if frames is not None and not frames.strip():
        from .errors import UsdWrinkleError

        raise UsdWrinkleError("frames is empty (None renders the stage's time range)")
    args.frames = frames
    actions = {action.dest: action for action in build_parser().commands[command]._actions}
    for name, value in options.items():
        setattr(args, name, _checked(name, value, actions.get(name)))
    args.debug = False
    args.library = True  # warnings through the library's logger (log.collect sees them)
    return args


def _checked(name: str, value, action):
    """``value`` as the command line would take it for option ``name``: its choices and
    its type (an int option refuses "wide" and 3.5), else UsdWrinkleError."""
    from .errors import UsdWrinkleError

    if action is None or value is None:
        return value
    if action.choices is not None and value not in action.choices:
        raise UsdWrinkleError(f"{name}={value!r} is not one of "
                              f"{', '.join(map(str, action.choices))}")
    kind = action.type
    if kind in (int, float) and (isinstance(value, bool) or not isinstance(value, (int, float))
                                 or (kind is int and not float(value).is_integer())):
        raise UsdWrinkleError(f"{name}={value!r} must be "
                              f"{'an integer' if kind is int else 'a number'}")
    if kind in (int, float):
        return kind(value)
    if action.nargs == 0 and not isinstance(value, bool):
        raise UsdWrinkleError(f"{name}={value!r} must be True or False")
    return value


def render(stage, output, frames=None, *, quiet: bool = True, **options) -> list[str]:
    """Render ``stage`` to ``output`` (a path with a '#' frame placeholder, or one file
    for one frame); returns the paths of the frames the shot now has on disk (written,
    or kept by ``skip_existing``). The options are render's: ``width`` (640), ``height``,
    ``camera``, ``samples`` (4), ``no_wrinkles``, ``all_meshes``, ``recompute``,
    ``relax_iterations``, ``history_start``, ``write_threads``, ``exr_compression``,
    ``exr_half``, ``skip_existing``, ``stats``, ``dask``, ``workers``, ``chunk``; and the
    composition options ``sublayer`` (a list of layers over the stage, strongest first),
    ``variant`` (a list of "/Prim{set=name}") and ``mask`` ("/A,/B")."""
    import os

    from .cli.render import render_shot

    args = _namespace("render", stage, output, frames, {"quiet": quiet, **options})
    return [path for path in render_shot(args) if os.path.isfile(path)]


def bake(stage, output, frames=None, *, quiet: bool = True, **options) -> str:
    """Bake the wrinkle fields of ``stage`` into the layer ``output`` (.usda, .usdc or
    .usd); returns its path. The options are bake's: ``with_points``, ``display_color``
    ("amplitude" or "compression"), ``sparse``, ``all_meshes``, ``relax_iterations``,
    ``history_start``, ``maps`` ("normal,height,amplitude" or a list), ``map_size``,
    ``map_dir``, ``map_format``, ``map_padding``, ``uv``, ``tangent_space``,
    ``map_layout``, ``map_displacement``, ``geometry``, ``levels``, ``samples_per_wavelength``,
    ``sublayer``, ``variant``, ``mask`` (as render's)."""
    if "maps" in options and options["maps"] is not None and \
            not isinstance(options["maps"], str):
        options["maps"] = ",".join(options["maps"])
    from .cli import bake as bake_command

    bake_command.run(_namespace("bake", stage, output, frames, {"quiet": quiet, **options}))
    return str(output)
