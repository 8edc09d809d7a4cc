"""Per-pixel comparison of two renders of the same shot (ours and a real client's)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Match:
    """How two 8-bit sRGB images agree over the pixels both cover fully."""

    pixels: int           # compared pixels
    correlation: float    # Pearson correlation of the RGB codes
    mean_abs: float       # mean absolute difference, in 8-bit codes
    p99_abs: float        # 99th percentile of the per-pixel largest channel difference
    iou: float            # intersection over union of the covered pixels

    def __str__(self) -> str:
        return (f"corr {self.correlation:.4f}, MAD {self.mean_abs:.2f}/255, "
                f"p99 {self.p99_abs:.0f}/255, IoU {self.iou:.3f} over {self.pixels} px")


def read_rgba8(path) -> np.ndarray:
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(str(path))
    # a file that cannot be read leaves the buffer uninitialised: OIIO 3's get_pixels
    # then returns an empty array, not None
    pixels = buf.get_pixels(oiio.UINT8) if buf.read() else None
    if pixels is None or pixels.size == 0:
        raise OSError(f"cannot read {path}: {buf.geterror()}")
    if pixels.shape[2] == 3:
        pixels = np.concatenate([pixels, np.full(pixels.shape[:2] + (1,), 255, np.uint8)], 2)
    return pixels


def eroded(mask: np.ndarray, pixels: int = 1) -> np.ndarray:
    """``mask`` shrunk by ``pixels`` (4-neighbourhood): silhouettes, which each renderer
    anti-aliases its own way, drop out."""
    for _ in range(pixels):
        inner = mask.copy()
        inner[1:] &= mask[:-1]
        inner[:-1] &= mask[1:]
        inner[:, 1:] &= mask[:, :-1]
        inner[:, :-1] &= mask[:, 1:]
        mask = inner
    return mask


def compare(ours, theirs, erode: int = 1) -> Match:
    """Compare two RGBA images (paths or (h, w, 4) uint8) over the pixels both cover
    fully (alpha 255), shrunk by ``erode`` pixels so that anti-aliased edges, which
    each renderer filters its own way, are left out."""
    a = read_rgba8(ours) if not isinstance(ours, np.ndarray) else ours
    b = read_rgba8(theirs) if not isinstance(theirs, np.ndarray) else theirs
    if a.shape != b.shape:
        raise ValueError(f"images of different sizes: {a.shape} and {b.shape}")
    cover_a, cover_b = a[..., 3] > 0, b[..., 3] > 0
    union = np.count_nonzero(cover_a | cover_b)
    iou = np.count_nonzero(cover_a & cover_b) / union if union else 1.0
    both = eroded((a[..., 3] == 255) & (b[..., 3] == 255), erode)
    x = a[both][:, :3].astype(np.float64)
    y = b[both][:, :3].astype(np.float64)
    if len(x) < 2:
        return Match(len(x), float("nan"), float("nan"), float("nan"), iou)
    diff = np.abs(x - y)
    correlation = float(np.corrcoef(x.reshape(-1), y.reshape(-1))[0, 1]) \
        if x.std() > 0 and y.std() > 0 else float(np.allclose(x, y))
    return Match(len(x), correlation, float(diff.mean()),
                 float(np.percentile(diff.max(axis=1), 99)), iou)


def side_by_side(images, path, labels=None, background=(77, 77, 77)) -> None:
    """Write RGBA images side by side (over a grey background) to ``path`` (PNG)."""
    import OpenImageIO as oiio

    tiles = []
    for image in images:
        rgba = read_rgba8(image) if not isinstance(image, np.ndarray) else image
        alpha = rgba[..., 3:4].astype(np.float32) / 255.0
        rgb = rgba[..., :3] * alpha + np.asarray(background, np.float32) * (1 - alpha)
        tiles.append(np.pad(rgb, ((0, 0), (0, 6), (0, 0)), constant_values=255))
    height = max(t.shape[0] for t in tiles)
    tiles = [np.pad(t, ((0, height - t.shape[0]), (0, 0), (0, 0)), constant_values=255)
             for t in tiles]
    out = np.concatenate(tiles, axis=1).round().clip(0, 255).astype(np.uint8)
    buf = oiio.ImageBuf(oiio.ImageSpec(out.shape[1], out.shape[0], 3, "uint8"))
    buf.set_pixels(oiio.ROI(), out)
    buf.write(str(path))
