"""usdwrinkle apply: author WrinkleAPI on meshes, with q painted from textures
(app/apply.py does the work)."""
from __future__ import annotations

from ..app import apply as schema  # the schema's fallbacks, for the help
from ..process.errors import print_stderr


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "apply", help="apply and author WrinkleAPI on meshes (q from textures, widths, profiles)",
        description="Apply WrinkleAPI to the meshes that PRIM_PATH names and author its "
                    "attributes. PRIM_PATH may be a pattern: '*' matches within a path "
                    "element, '**' matches any number of elements (/World/**/Shirt*). "
                    "Edits go to the stage's root layer, or with -o to an override layer of "
                    "sparse overs that sublayers nothing. Every value is checked with the "
                    "rules of 'usdwrinkle check'; a bad one is refused and nothing is written.")
    p.add_argument("stage", help="the USD stage")
    p.add_argument("prim_paths", nargs="+", metavar="PRIM_PATH", help="mesh paths or patterns")
    p.add_argument("-o", "--output", metavar="LAYER",
                   help="write the edits to this override layer (created or updated) instead "
                        "of the root layer")
    p.add_argument("--width", type=float, metavar="W",
                   help="rest wavelength W (scene units); without it, and with no "
                        "primvars:wrinkle:width authored, a mesh uses its cloth's fold "
                        "wavelength (--cloth) through the stage's metersPerUnit")
    p.add_argument("--cloth", choices=schema.CLOTH_TOKENS,
                   help="wrinkle:cloth, the cloth whose fold wavelength is the fallback W: "
                        + ", ".join(f"{name} {100 * metres:g} cm"
                                    for name, metres in schema.CLOTH_WIDTHS_M.items())
                        + f"; mesh: {schema.WIDTH_EDGE_MULTIPLE:g} x the mean rest edge "
                        f"length (default {schema.DEFAULT_CLOTH})")
    p.add_argument("--slack", type=float, metavar="C",
                   help="wrinkle:slack in [0, 0.9], the compression before the crests "
                        "settle; folds are drawn from "
                        f"{schema.DRAWN_SLACK:g} x it on (default {schema.DEFAULT_SLACK:g}; 0: the "
                        "paper's law)")
    p.add_argument("--crest-damping", type=float, metavar="DEGREES",
                   help="wrinkle:crestDamping in [0, 45], the band in degrees within which "
                        "the compression direction holds while the strain turns, followed "
                        f"beyond it (default {schema.DEFAULT_CREST_DAMPING:g}; 0: none)")
    p.add_argument("--irregularity", type=float, metavar="SPREAD",
                   help="wrinkle:irregularity in [0, 0.5]: how unequal the folds are (the "
                        "coefficient of variation of their width; their crests meander and "
                        "the wider ones stand taller; about 0.3 in the cloth referee's "
                        f"folds). Default {schema.DEFAULT_IRREGULARITY:g}; 0: the paper's "
                        "regular waves")
    p.add_argument("--held-from-primvar", metavar="NAME",
                   help="author primvars:wrinkle:held from this float primvar of the mesh "
                        "(a painted seam or clamp weight in [0, 1], vertex interpolation; "
                        "what damps the waves is a held edge, both its ends held: a lone "
                        "held point is a pin, at which the cloth gathers)")
    p.add_argument("--amplitude-scale", type=float, metavar="S",
                   help="amplitude scale s (default 1: the amplitude law of docs/method.md)")
    p.add_argument("--biaxial", type=float, metavar="WEIGHT",
                   help="wrinkle:biaxial in [0, 1]: a second wave where the cloth is "
                        "compressed both ways (0: off, the default)")
    p.add_argument("--tension", type=float, metavar="FACTOR",
                   help="wrinkle:tension >= 0: tension wrinkles along a pull (0: off, the "
                        "default)")
    p.add_argument("--tension-threshold", type=float, metavar="STRAIN",
                   help="wrinkle:tensionThreshold in [0, 1]: the strain where tension "
                        "wrinkles begin (fallback 0.02)")
    p.add_argument("--profile", metavar="NAME|FILE",
                   help="height profile: fold (the default), cosine, sharp, rounded, box, "
                        "triangle, or a text file of heights over one period (or 'theta "
                        "height' pairs)")
    p.add_argument("--q", metavar="X,Y,Z:AMOUNT",
                   help="uniform rest-space direction, projected onto each vertex's tangent "
                        "plane, with |q| = AMOUNT")
    p.add_argument("--q-from-texture", metavar="IMAGE",
                   help="flow map: RG = tangent direction in (u, v) as 2c-1, v up")
    p.add_argument("--uv", default="st", metavar="PRIMVAR",
                   help="texture coordinates for the texture options (st)")
    p.add_argument("--amount-channel", choices=("R", "G", "B", "A"), type=str.upper,
                   help="flow map channel with the amount (default: the decoded vector's length)")
    p.add_argument("--q-from-primvar", metavar="NAME",
                   help="convert a painted vertex primvar (vector, or colour as 2c-1) into q")
    p.add_argument("--width-from-texture", metavar="IMAGE",
                   help="grey map that scales the width per vertex (width becomes vertex)")
    p.add_argument("--clear-q", action="store_true", help="remove the painted q")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..app.apply import ApplyJob
    from ..app.options import ApplyOptions

    options = ApplyOptions(
        stage=args.stage, prim_paths=tuple(args.prim_paths), output=args.output,
        width=args.width, cloth=args.cloth, slack=args.slack,
        crest_damping=args.crest_damping, irregularity=args.irregularity,
        held_from_primvar=args.held_from_primvar,
        amplitude_scale=args.amplitude_scale, biaxial=args.biaxial, tension=args.tension,
        tension_threshold=args.tension_threshold, profile=args.profile, q=args.q,
        q_from_texture=args.q_from_texture, uv=args.uv, amount_channel=args.amount_channel,
        q_from_primvar=args.q_from_primvar, width_from_texture=args.width_from_texture,
        clear_q=args.clear_q)
    result = ApplyJob(options).run()
    print_stderr(f"usdwrinkle: applied WrinkleAPI to {result.meshes} mesh(es) in "
                 f"{result.layer}")
    return 0
