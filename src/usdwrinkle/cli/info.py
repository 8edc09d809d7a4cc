"""usdwrinkle info: versions, the GL renderer and the environment other USD tools need."""
from __future__ import annotations

import os
import platform


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "info", help="print versions, the GL renderer and the environment usdview needs",
        description="Print usdwrinkle's and its libraries' versions, the GL renderer it would "
                    "use, and the environment other USD processes (usdview, usdcat) need to "
                    "see the WrinkleAPI schema and the Wrinkles menu. Exits 1 when no GL "
                    "context can be made or the schema is not usable, so it serves as a "
                    "render node's health check. USDWRINKLE_EGL_DEVICE picks the GPU on a "
                    "multi-GPU node (EGL's device index, default 0); USDWRINKLE_GL_BACKEND "
                    "picks moderngl's backend (default egl).")
    p.add_argument("--no-gl", action="store_true",
                   help="do not create a GL context (and do not check it)")
    p.set_defaults(run=run)


def run(args) -> int:
    import moderngl
    import numpy
    import OpenImageIO
    from pxr import Usd

    from .. import __version__
    from ..app.environment import register_schema, schema_dir
    from ..process.errors import GLContextError

    print(f"usdwrinkle {__version__}")
    print(f"python {platform.python_version()} ({platform.platform()})")
    print(f"usd-core {_usd_core_version()} (OpenUSD "
          f"{'.'.join(str(v) for v in Usd.GetVersion())})")
    print(f"moderngl {moderngl.__version__}, numpy {numpy.__version__}, "
          f"OpenImageIO {OpenImageIO.__version__}")
    healthy = register_schema()
    print(f"WrinkleAPI schema: {'registered' if healthy else 'NOT usable'} "
          f"({schema_dir()})")
    if not args.no_gl:
        from ..app.environment import renderer_info
        try:
            info = renderer_info()
            print(f"GL renderer: {info['renderer']}; {info['version']}")
        except GLContextError as exc:
            print(f"GL renderer: unavailable: {exc.one_line()}")
            healthy = False
    for line in environment_lines():
        print(line)
    return 0 if healthy else 1


def _usd_core_version() -> str:
    """The usd-core package's own version (26.11), as pip names it."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("usd-core")
    except PackageNotFoundError:
        return "not installed as usd-core"


def environment_lines() -> list[str]:
    """The exact environment usdview needs for the schema and the Wrinkles menu."""
    import usdwrinkle

    from ..app.environment import schema_dir
    from ..usdview import plugin_dir

    def joined(name, *dirs, last=False):
        current = os.environ.get(name, "")
        parts = [d for d in dirs if d not in current.split(os.pathsep)]
        ordered = ([current] if current else []) + parts if last else \
            parts + ([current] if current else [])
        return os.pathsep.join(ordered)

    package_parent = os.path.dirname(os.path.dirname(os.path.abspath(usdwrinkle.__file__)))
    plugin_path = joined("PXR_PLUGINPATH_NAME", schema_dir(), plugin_dir())
    # a non-editable install's folder is a site-packages that also holds usd-core's pxr:
    # first on PYTHONPATH it would shadow the studio's USD, whose pxr has Usdviewq
    shadows = os.path.isdir(os.path.join(package_parent, "pxr"))
    import sys

    return ["environment for other USD processes (usdview, usdcat):",
            f"  export PXR_PLUGINPATH_NAME={plugin_path}",
            f"  export PYTHONPATH={joined('PYTHONPATH', package_parent, last=shadows)}"
            + ("  # last: this folder also holds usd-core's pxr, which must not come "
               "before usdview's" if shadows else ""),
            # usdview's Python may lack numpy, moderngl and OpenImageIO: the plugin's
            # commands then run usdwrinkle in this Python
            f"  export USDWRINKLE_PYTHON={sys.executable}"]
