"""usdwrinkle bake STAGE OUTPUT_LAYER: write the wrinkle fields back to USD."""
from __future__ import annotations

from ..app.options import (
    BAKED_NAMES_TEXT,
    GEOMETRY_DEFAULTS,
    MAP_DEFAULTS,
    MAP_LAYOUTS,
    TANGENT_SPACES,
)
from ..app.options import MAP_ST_NAME as MAP_ST
from ..process.errors import print_stderr
from .common import Reporter, add_shot_args, report_to


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "bake", help="bake the wrinkle fields of every frame into a USD layer",
        description="Compute the wrinkles of a stage and write them as per-vertex primvars "
                    f"({BAKED_NAMES_TEXT}; "
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
                           "over s*1.5*W/4, about the fold law's height of cloth "
                           "crushed flat: a [0, 1] mask), parallax (the texture deformation: "
                           "three float EXRs and a MaterialX network, render context mtlx, "
                           "that moves the look's textures with the folds for any camera; "
                           "Storm and MaterialX renderers show it, others keep the "
                           "UsdPreviewSurface)")
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
    maps.add_argument("--map-layout", choices=MAP_LAYOUTS,
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
                             f"(default {GEOMETRY_DEFAULTS.samples_per_wavelength:g}) on "
                             "the fold profile; a mesh whose profile turns faster (sharp, "
                             "box, a curve) gets up to 2x as many")
    p.add_argument("--sparse", action="store_true",
                   help="write the overs alone, without sublayering the input")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    # The bake is one process on purpose: each frame's phases start from the previous
    # frame's (phase history), so its frames cannot be computed apart (README, farms).
    p.set_defaults(run=run)


def bake_job(args):
    """The app.BakeJob of the command's options."""
    from ..app.bake import BakeJob
    from ..app.options import BakeOptions
    from .render import shot_of

    options = BakeOptions(
        with_points=args.with_points, display_color=args.display_color, sparse=args.sparse,
        maps=args.maps, map_size=args.map_size, map_dir=args.map_dir,
        map_format=args.map_format, map_padding=args.map_padding, map_layout=args.map_layout,
        uv=args.uv, tangent_space=args.tangent_space, map_displacement=args.map_displacement,
        geometry=args.geometry, levels=args.levels,
        samples_per_wavelength=args.samples_per_wavelength)
    return BakeJob(shot_of(args), args.output, args.frames, options)


def run(args) -> int:
    job = bake_job(args)
    with Reporter(args.quiet, library=getattr(args, "library", False)) as reporter:
        report_to(job, reporter, args)
        result = job.run()
    if not args.quiet:
        print_stderr(f"usdwrinkle: baked {result.count} mesh(es) x {len(result.frames)} "
                     f"frame(s) to {args.output} in {result.elapsed:.1f} s")
        for path, text in result.meshes.items():
            print_stderr(f"  {path}: {text}")
    return 0
