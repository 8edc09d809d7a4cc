"""usdwrinkle info: versions, the GL renderer and the environment other USD tools need."""
from __future__ import annotations

import os
import platform


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("info", help="print versions, the GL renderer and the environment "
                                           "usdview needs")
    p.add_argument("--no-gl", action="store_true", help="do not create a GL context")
    p.set_defaults(run=run)


def run(args) -> int:
    import moderngl
    import numpy
    import OpenImageIO
    from pxr import Usd

    from .. import __version__, schema
    from ..errors import GLContextError

    print(f"usdwrinkle {__version__}")
    print(f"python {platform.python_version()} ({platform.platform()})")
    print(f"usd-core {'.'.join(str(v) for v in Usd.GetVersion())}")
    print(f"moderngl {moderngl.__version__}, numpy {numpy.__version__}, "
          f"OpenImageIO {OpenImageIO.__version__}")
    print(f"WrinkleAPI schema: {'registered' if schema.register() else 'NOT usable'} "
          f"({schema.schema_dir()})")
    if not args.no_gl:
        from ..render.context import renderer_info
        try:
            info = renderer_info()
            print(f"GL renderer: {info['renderer']}; {info['version']}")
        except GLContextError as exc:
            print(f"GL renderer: unavailable: {exc.one_line()}")
    current = os.environ.get("PXR_PLUGINPATH_NAME", "")
    value = schema.schema_dir() + (os.pathsep + current if current else "")
    print("environment for other USD processes (usdview, usdcat):")
    print(f"  export PXR_PLUGINPATH_NAME={value}")
    return 0
