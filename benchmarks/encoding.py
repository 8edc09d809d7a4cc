"""Encoding frames on every core (issue 45): how the writer's threads scale, and what each
EXR compression costs.

    python -m benchmarks.encoding

(``python -m benchmarks`` runs it too, in its CPU render nodes section.)

The shirt's last frame is rendered once at 1920x1080 as render writes it (an EXR with every
AOV, colour and normals half float; and the 8-bit PNG), then the same frame is encoded 16
times through usdwrinkle's own encoder (outputs/images.encode_frame, in memory) by a pool
of 1, 2, 4 ... threads up to the cores: the frames per second show whether the encoders
release the GIL. Each EXR compression is timed the same way with every core, with the
file's size.
"""
from __future__ import annotations

import datetime
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHIRT = ROOT / "sample_stages" / "shirt.usda"
FRAMES = 16


def frame_images(width: int, height: int, ctx=None) -> dict:
    """{extension: ResolvedImage} of the shirt's frame 24."""
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.outputs.images import layout_for
    from usdwrinkle.render.request import FrameRequest

    engine = WrinkleEngine(str(SHIRT), ctx=ctx)
    try:
        return {ext: engine.render(24.0, FrameRequest(width, height,
                                                      layout=layout_for(f"x{ext}")))
                for ext in (".exr", ".png")}
    finally:
        engine.release()


def encode_rate(image, ext: str, threads: int, compression: str = "zip",
                frames: int = FRAMES) -> tuple[float, int]:
    """(frames per second, bytes of one file) encoding ``frames`` copies with ``threads``."""
    from usdwrinkle.outputs.images import encode_frame, memory_file

    def one(_index: int) -> int:
        with memory_file(ext) as scratch:
            encode_frame(scratch, image, f"frame{ext}", compression)
            return os.path.getsize(scratch)

    started = time.perf_counter()
    with ThreadPoolExecutor(threads) as pool:
        sizes = list(pool.map(one, range(frames)))
    return frames / (time.perf_counter() - started), sizes[0]


def measure(quick: bool = False, ctx=None) -> dict:
    from usdwrinkle.outputs.images import EXR_COMPRESSIONS
    from usdwrinkle.outputs.writer import cores

    width, height = (480, 270) if quick else (1920, 1080)
    frames = 4 if quick else FRAMES
    images = frame_images(width, height, ctx)
    counts = sorted({1, *[2 ** i for i in range(1, 7) if 2 ** i <= cores()], cores()})
    threads = {ext: {str(n): encode_rate(images[ext], ext, n, frames=frames)[0]
                     for n in counts} for ext in (".exr", ".png")}
    compressions = {name: encode_rate(images[".exr"], ".exr", cores(), name, frames)
                    for name in EXR_COMPRESSIONS}
    return {"cores": cores(), "width": width, "height": height, "frames": frames,
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "threads": threads, "compressions": compressions}


def markdown(result: dict) -> list[str]:
    counts = sorted(result["threads"][".exr"], key=int)
    lines = ["### Encoding on every core", "",
             f"The shirt's frame 24 at {result['width']}x{result['height']} as `render` "
             f"writes it, encoded {result['frames']} times in memory by a pool of threads "
             f"(outputs/images.encode_frame), on {result['cores']} core(s), "
             f"{result['date']} (`python -m benchmarks.encoding`). Frames per second: both "
             "encoders release the GIL, so the writer's threads encode in parallel; render "
             "uses every core but one by default (`--write-threads`).", "",
             "| format | " + " | ".join(f"{n} thread(s)" for n in counts) + " |",
             "|---|" + "---|" * len(counts)]
    for ext, name in ((".exr", "EXR (zip, every AOV)"), (".png", "PNG (8-bit sRGB)")):
        lines.append(f"| {name} | " + " | ".join(f"{result['threads'][ext][n]:.1f}"
                                                  for n in counts) + " |")
    lines += ["", f"EXR compressions, {result['cores']} thread(s): zip stays the default, "
              "the fastest lossless compression that keeps the files small; none is the "
              "fastest to encode and about 8 times larger (a fast local disk may prefer "
              "it); dwaa is lossy.", "",
              "| compression | frames per second | MB a frame |", "|---|---|---|"]
    for name, (rate, size) in result["compressions"].items():
        lines.append(f"| {name} | {rate:.1f} | {size / 1e6:.1f} |")
    return lines + [""]


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else argv
    print("\n".join(markdown(measure(quick="--quick" in args))))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
