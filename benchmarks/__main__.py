"""python -m benchmarks (``usdwrinkle bench`` runs this in a child process)."""
import sys

from benchmarks import main

code = main()
if "usdwrinkle.render.context" in sys.modules:
    from usdwrinkle.render.context import release_context

    release_context()  # the one GL context of the process, released cleanly
sys.exit(code)
