"""usdwrinkle bake STAGE OUTPUT_LAYER: write the wrinkle fields back to USD."""
from __future__ import annotations

import dataclasses
import os
import time

from ..errors import UsdWrinkleError, print_stderr
from ..geometry.options import GeometryOptions
from ..maps.options import LAYOUTS, TANGENT_SPACES, MapOptions
from ..schema import MAP_ST, baked_names_text
from .common import (
    Reporter,
    add_shot_args,
    check_stage_args,
    composition_of,
    refuse_overwriting_inputs,
    start_engine,
)
from .frames import parse_frame_spec

MAP_DEFAULTS = MapOptions()
GEOMETRY_DEFAULTS = GeometryOptions()


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "bake", help="bake the wrinkle fields of every frame into a USD layer",
        description="Compute the wrinkles of a stage and write them as per-vertex primvars "
                    f"({baked_names_text()}; "
                    "interpolation vertex) with a time sample per frame. By default the "
                    "output layer sublayers the input, so 'usdview OUTPUT_LAYER' shows the "
                    "shot with the baked data. --maps adds per-frame wrinkle maps bound in a "
                    "UsdPreviewSurface material per mesh; --geometry adds a displaced render "
                    "mesh per wrinkled mesh, with the coarse mesh as its proxy.")
    add_shot_args(p, "the layer to write (.usda, .usdc or .usd)")
    p.add_argument("--with-points", action="store_true",
                   help="also write the posed points and extent in each mesh's local space, "
                        "and the posed normals of the meshes that author normals, in their "
                        "own attribute (as UsdSkelBakeSkinning); each baked skinned mesh then "
                        "binds no skeleton, so the composed stage is not skinned twice "
                        "(--maps implies it)")
    p.add_argument("--display-color", choices=("amplitude", "compression"),
                   help="also write primvars:displayColor (vertex) as a viridis ramp of that "
                        "field, for usdview's default shading")
    maps = p.add_argument_group(
        "wrinkle maps", "per-frame texture maps of the wrinkles, bound in a UsdPreviewSurface "
                        "material per mesh, for renderers that read textures (README: maps)")
    maps.add_argument("--maps", metavar="KINDS",
                      help="comma-separated: normal (tangent-space normal, 0.5n+0.5), height "
                           "(signed height in scene units, float EXR), amplitude (amplitude "
                           "over s*g*W/4, g the curved-cloth gain: a [0, 1] "
                           "mask)")
    maps.add_argument("--map-size", type=int, metavar="N",
                      help="texels per side of each map (per UDIM tile); default "
                           f"{MAP_DEFAULTS.size}")
    maps.add_argument("--map-dir", metavar="DIR",
                      help="where the maps go (default: <layer name>_maps beside the layer); "
                           "the layer names them relative to itself")
    maps.add_argument("--map-format", choices=("png", "exr"),
                      help="normal and amplitude maps as 16-bit PNG (default) or float EXR "
                           "(usdview's Storm reads a 16-bit PNG at 8 bits); the height map "
                           "is always float EXR")
    maps.add_argument("--map-padding", type=int, metavar="N",
                      help="texels by which UV islands are grown, so that filtering at their "
                           f"borders does not reach the background; default "
                           f"{MAP_DEFAULTS.padding}")
    maps.add_argument("--map-layout", choices=LAYOUTS,
                      help="islands: every face its own island in texture coordinates of "
                           f"the bake's own (primvars:{MAP_ST}), so that usdview's Storm "
                           "decodes each face in one continuous frame and never reads a "
                           "neighbour's texels; asset: the mesh's own texture coordinates "
                           "(--uv), so that the maps line up with its textures and Blender, "
                           "which decodes normal maps in the mesh's first UV set, decodes "
                           "them. Given, the bake writes one map set in it, bound for every "
                           "purpose (docs/method.md: map layout)")
    maps.add_argument("--uv", metavar="NAME",
                      help="the texture coordinates (primvar) the maps are laid out in "
                           f"unless --map-layout islands; default {MAP_DEFAULTS.uv}")
    maps.add_argument("--tangent-space", choices=TANGENT_SPACES,
                      help="the tangent frame the normal maps are written in: triangle (per "
                           "triangle, as usdview's Storm and usdwrinkle decode them) or "
                           "mikktspace (per vertex, as Blender's Cycles and EEVEE, Unreal, "
                           "Substance and glTF viewers decode them). Given, the bake writes "
                           "one map set in it, bound for every purpose. Without it and "
                           "--map-layout, two sets: mikktspace in the mesh's UVs for final "
                           "renderers (material:binding) and triangle in islands for "
                           "usdview's Storm (material:binding:preview) (docs/method.md: "
                           "tangent frames)")
    maps.add_argument("--map-displacement", action="store_true", default=None,
                      help="also bind the height map to UsdPreviewSurface's "
                           "inputs:displacement, for renderers that subdivide and displace "
                           "at render time (Storm displaces the coarse corners and keeps "
                           "their normals: streaks)")
    geometry = p.add_argument_group(
        "displaced geometry", "a finer render mesh per wrinkled mesh that carries the "
                              "wrinkles as real displacement, with the coarse mesh as its "
                              "proxy (README: displaced geometry)")
    geometry.add_argument("--geometry", action="store_true",
                          help="write <mesh>_wrinkled (purpose render; the coarse mesh "
                               "becomes purpose proxy)")
    levels = geometry.add_mutually_exclusive_group()
    levels.add_argument("--levels", type=int, metavar="N",
                        help="midpoint subdivision levels (each splits every triangle in 4); "
                             "default: the fewest that keep fine rest edges within W/S and "
                             "give the shot's waves S samples per wavelength "
                             "(S: --samples-per-wavelength)")
    levels.add_argument("--samples-per-wavelength", type=float, metavar="S",
                        help="fine vertices per wavelength the default levels aim for "
                             f"(default {GEOMETRY_DEFAULTS.samples_per_wavelength:g})")
    p.add_argument("--sparse", action="store_true",
                   help="write the overs alone, without sublayering the input")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    # The bake is one process on purpose: each frame's phases start from the previous
    # frame's (phase history), so its frames cannot be computed apart (README, farms).
    p.set_defaults(run=run)


def _given(args, flags: dict) -> dict:
    """{field: value} of the options in ``flags`` (flag -> field) that were given."""
    return {field: getattr(args, flag.lstrip("-").replace("-", "_"))
            for flag, field in flags.items()
            if getattr(args, flag.lstrip("-").replace("-", "_")) is not None}


MAP_FLAGS = {"--map-size": "size", "--map-dir": "folder", "--map-format": "fmt",
             "--map-padding": "padding", "--uv": "uv", "--tangent-space": "tangent_space",
             "--map-layout": "layout",
             "--map-displacement": "displacement"}
GEOMETRY_FLAGS = {"--levels": "levels", "--samples-per-wavelength": "samples_per_wavelength"}


def _refuse_without(args, flags: dict, needed: str) -> None:
    given = [flag for flag in flags if getattr(args, flag.lstrip("-").replace("-", "_"))
             is not None]
    if given:
        raise UsdWrinkleError(f"{', '.join(given)} need {needed}")


def map_options(args):
    """MapOptions from --maps and its options (None without --maps); what is not given
    keeps MapOptions' default."""
    if args.maps is None:
        _refuse_without(args, MAP_FLAGS, "--maps")
        return None
    from ..maps.bake import check_map_options
    from ..maps.files import parse_map_kinds

    if args.map_layout == "islands" and args.uv is not None:
        raise UsdWrinkleError("--uv names the texture coordinates of --map-layout asset; "
                              "--map-layout islands lays the maps out in their own")
    options = dataclasses.replace(MAP_DEFAULTS, kinds=parse_map_kinds(args.maps),
                                  uv_named=args.uv is not None, **_given(args, MAP_FLAGS))
    check_map_options(options)
    return options


def geometry_options(args):
    """GeometryOptions from --geometry and its options (None without --geometry)."""
    if not args.geometry:
        _refuse_without(args, GEOMETRY_FLAGS, "--geometry")
        return None
    from ..geometry.bake import check_geometry_options

    options = dataclasses.replace(GEOMETRY_DEFAULTS, **_given(args, GEOMETRY_FLAGS))
    check_geometry_options(options)
    return options


def check_map_folder(folder: str) -> None:
    """Refuse a map folder that cannot be written, before any work; one that does not
    exist yet is made only when the maps are committed (a failed bake leaves none)."""
    from ..outputs.atomic import check_writable

    if os.path.exists(folder) and not os.path.isdir(folder):
        raise UsdWrinkleError(f"cannot write maps to '{folder}': it is a file, not a folder")
    probe = folder if os.path.isdir(folder) else os.path.dirname(os.path.abspath(folder))
    check_writable([os.path.join(probe, ".usdwrinkle-maps-probe")])


def run(args) -> int:
    from ..outputs.layers import check_layer_path

    check_stage_args(args)
    maps = map_options(args)
    geometry = geometry_options(args)
    refuse_overwriting_inputs(args.stage, [args.output])
    check_layer_path(args.output)
    with Reporter(args.quiet, library=getattr(args, "library", False)) as reporter:
        return _bake(args, reporter, maps, geometry)


def _bake(args, reporter, maps, geometry) -> int:
    from ..outputs.atomic import check_writable
    from ..scene.stage import (
        inherited_range_note,
        open_stage,
        outside_range_note,
        stage_frames,
    )
    from ..shot import BakeRequest, bake_layer

    # everything that can be refused without the GPU is checked first
    stage = open_stage(args.stage, composition_of(args))
    refuse_overwriting_inputs(args.stage, [args.output], stage)
    check_writable([args.output])
    if maps is not None:
        check_map_folder(maps.folder_for(args.output))
    frames = parse_frame_spec(args.frames) if args.frames else stage_frames(stage)
    if not args.frames and (note := inherited_range_note(stage)):
        reporter.warn(note)
    # a bake always computes: fields already baked into the input are not its input
    engine = start_engine(args, reporter, stage, use_baked=False)
    if args.frames and args.history_start is None and engine.wrinkled_paths and \
            (note := outside_range_note(stage, frames)):
        reporter.warn(note)
    try:
        if maps is not None:
            from ..maps.bake import check_map_options

            check_map_options(maps, engine.max_texture_size)
        engine.check_relax_work(frames)  # a refusal: before the header
        reporter.header(args.command, args.stage)
        started = time.perf_counter()
        request = BakeRequest(args.stage, args.output, tuple(frames), args.frames,
                              with_points=args.with_points, display_color=args.display_color,
                              sparse=args.sparse, maps=maps, geometry=geometry)
        count = bake_layer(engine, request,
                           progress=lambda items: reporter.progress(items, "bake"),
                           survey_progress=lambda items: reporter.progress(items, "survey"))
        if not args.quiet:
            from ..scene.params import width_summary

            print_stderr(f"usdwrinkle: baked {count} mesh(es) x {len(frames)} frame(s) to "
                  f"{args.output} in {time.perf_counter() - started:.1f} s")
            for path, record in sorted(engine.meshes.items()):
                if record.wrinkled:
                    print_stderr(f"  {path}: {width_summary(record.params)['text']}")
    finally:
        engine.release()
    return 0
