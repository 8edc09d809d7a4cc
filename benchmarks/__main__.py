"""python -m benchmarks: the same as usdwrinkle bench."""
import sys

from benchmarks import main

sys.exit(main())
