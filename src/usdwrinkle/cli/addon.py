"""usdwrinkle blender-addon: where the Blender add-on is, or a copy of it."""
from __future__ import annotations


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "blender-addon",
        help="print the Blender add-on's path, or copy it into a folder",
        description="usdwrinkle's Blender add-on imports the MaterialX wrinkle network of "
                    "'bake --maps normal,parallax' as Blender shader nodes, so that Cycles "
                    "and EEVEE bend the normals and move the textures with the folds, as "
                    "Storm does, and skins UsdSkel's dual-quaternion meshes by Blender's "
                    "dual quaternions (Preserve Volume), which Blender's importer does not "
                    "(README: 'The texture deformation in Blender'). Without "
                    "options this prints the add-on's file, for Blender's Edit > "
                    "Preferences > Add-ons > Install from Disk. It needs Blender 4.2 or "
                    "later (tested with bpy 5.0.1).")
    p.add_argument("--copy", metavar="DIR",
                   help="copy the add-on (usdwrinkle_blender.py) into DIR, for example "
                        "Blender's scripts/addons folder or a studio's shared add-on folder; "
                        "prints the copy's path")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..app.environment import blender_addon, copy_blender_addon

    print(copy_blender_addon(args.copy) if args.copy else blender_addon())
    return 0
