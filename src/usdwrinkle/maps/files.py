"""Wrinkle map files: names, UDIM tiles, encoding, and the all-or-nothing commit.

Every frame has its own files (``DIR/<mesh>.normal.0024.png``; with UDIM tiles
``DIR/<mesh>.normal.<UDIM>.0024.png``): renderers notice a changed texture by its name,
not by its time stamp. Maps are encoded into a staging folder beside the map folder and
moved into it only when every frame is done (:class:`MapStaging`), so an error or an
interrupt leaves no partial map set, and the layer that names them is written after.
"""
from __future__ import annotations

import os
import re
import shutil

import numpy as np

from ..outputs.atomic import signals_held, sweep_dead, write_error
from ..outputs.images import copy_complete, encode_file, memory_file
from ..process.errors import UsdWrinkleError
from ..process.timecode import frame_text

#: the maps ``bake --maps`` can write
MAP_KINDS = ("normal", "height", "amplitude", "parallax")
#: the files the parallax kind writes (float EXR, the mesh's local space): the bent normal
#: n', and the height times the gradients of the texture's s and t (maps/raster.MapPixels)
PARALLAX_FILES = ("parallaxN", "parallaxS", "parallaxT")
#: each file kind's image in maps/raster.MapPixels
PIXELS = {"normal": "normal", "height": "height", "amplitude": "amplitude",
          "parallaxN": "bent", "parallaxS": "hs", "parallaxT": "ht"}


def file_kinds(kinds) -> tuple[str, ...]:
    """The file kinds ``kinds`` (MAP_KINDS) write: parallax is three files."""
    return tuple(part for kind in kinds
                 for part in (PARALLAX_FILES if kind == "parallax" else (kind,)))
MAP_FORMATS = ("png", "exr")
UDIM_TOKEN = "<UDIM>"
#: UDIM tiles are 1001 + u + 10 v, u in 0..9; v in 0..9 here (draw.glsl's tile table)
UDIM_COLUMNS = 10
UDIM_ROWS = 10
STAGING_PREFIX = ".usdwrinkle-maps."
PNG_COMPRESSION = 1


def parse_map_kinds(text: str) -> tuple[str, ...]:
    """``normal,height`` -> ('normal', 'height'), in MAP_KINDS order; refuses unknowns."""
    kinds = [part.strip() for part in text.split(",") if part.strip()]
    unknown = [kind for kind in kinds if kind not in MAP_KINDS]
    if unknown or not kinds:
        raise UsdWrinkleError(f"`maps` takes a comma-separated list of {', '.join(MAP_KINDS)}"
                              f" (got '{text}')")
    return tuple(kind for kind in MAP_KINDS if kind in kinds)


def extension(kind: str, fmt: str) -> str:
    """The height and parallax maps are always float EXR (signed, in scene units); the
    others follow ``--map-format``."""
    return ".exr" if kind == "height" or kind in PARALLAX_FILES or fmt == "exr" else ".png"


#: the names a bake's material scope holds besides the meshes' (outputs/layers.py: the
#: display-colour ramp)
RESERVED_NAMES = ("DisplayColor",)
#: the suffixes the map sets add to a mesh's name for their materials (maps/options.py)
SET_SUFFIXES = ("", "_preview")


def mesh_file_names(paths, taken=()) -> dict[str, str]:
    """Mesh prim path -> a name for its map files and materials: the prim's name, with as
    many parent names as it takes to tell meshes of the same name apart, in file-safe
    characters. One allocator for every name a bake makes: no two meshes get one name,
    no mesh's name with a set's suffix (``Cloth`` + ``_preview``) is another's, and none
    is in ``taken`` (names the bake's material scope already holds, and RESERVED_NAMES):
    a clash gets ``_2``, ``_3``... in the order of the prim paths, so names are stable."""
    parts = {path: [p for p in path.split("/") if p] for path in paths}
    wanted = {}
    for path, segments in parts.items():
        depth = 1
        while True:
            name = "_".join(segments[-depth:])
            clash = [other for other, o in parts.items() if other != path and
                     "_".join(o[-depth:]) == name]
            if not clash or depth >= len(segments):
                break
            depth += 1
        wanted[path] = re.sub(r"[^A-Za-z0-9_.-]", "_", name)
    used = {name for name in (*taken, *RESERVED_NAMES)}
    names = {}
    for path in sorted(parts):  # the ordering that keeps names stable between bakes
        base = wanted[path] or "mesh"
        name, count = base, 1
        while any(f"{name}{suffix}" in used for suffix in SET_SUFFIXES) or any(
                name == f"{other}{suffix}" for other in names.values()
                for suffix in SET_SUFFIXES[1:]):
            count += 1
            name = f"{base}_{count}"
        names[path] = name
        used.update(f"{name}{suffix}" for suffix in SET_SUFFIXES)
    return {path: names[path] for path in parts}


def uv_tiles(corner_uv: np.ndarray) -> tuple[list[tuple[int, int]], int]:
    """(the UDIM tiles (u, v) the triangles lie in, by their UV centroid; the number of
    triangles outside tiles 1001..1100). [(0, 0)] alone means no UDIM set."""
    if len(corner_uv) == 0:
        return [(0, 0)], 0
    centroid = np.asarray(corner_uv, np.float64).reshape(-1, 3, 2).mean(axis=1)
    tile = np.floor(centroid).astype(np.int64)
    finite = np.all(np.isfinite(centroid), axis=1)
    inside = finite & (tile[:, 0] >= 0) & (tile[:, 0] < UDIM_COLUMNS) & \
        (tile[:, 1] >= 0) & (tile[:, 1] < UDIM_ROWS)
    tiles = sorted({(int(u), int(v)) for u, v in tile[inside]}, key=lambda t: (t[1], t[0]))
    return tiles or [(0, 0)], int(np.count_nonzero(~inside))


def udim_number(tile: tuple[int, int]) -> int:
    return 1001 + tile[0] + UDIM_COLUMNS * tile[1]


def map_file_name(stem: str, kind: str, frame_text: str | None, fmt: str, udim: bool) -> str:
    """``Shirt.normal.0024.png``; with UDIM tiles ``Shirt.normal.<UDIM>.0024.png``;
    without a frame (a stage with no time samples) ``Shirt.normal.png``."""
    parts = [stem, kind] + ([UDIM_TOKEN] if udim else []) + \
        ([frame_text] if frame_text else [])
    return ".".join(parts) + extension(kind, fmt)


def tile_file_name(name: str, tile: tuple[int, int]) -> str:
    return name.replace(UDIM_TOKEN, str(udim_number(tile)))


def _spec(width: int, height: int, channels: int, data_format: str, names=None):
    import OpenImageIO as oiio

    spec = oiio.ImageSpec(width, height, channels, data_format)
    if names:
        spec.channelnames = tuple(names)
    return spec


def encode_map(path: str, kind: str, pixels: np.ndarray, final_path: str) -> None:
    """Encode one map (row 0 at t = 0) to ``path``: the normal as 0.5 n + 0.5 (16-bit PNG
    or float EXR, read back with scale 2 and bias -1), the height and the parallax maps
    as float EXR, the amplitude as a 16-bit grey PNG or a float EXR."""
    image = np.ascontiguousarray(pixels[::-1])  # files store the top row first
    if kind == "normal":
        image = 0.5 * image + 0.5
    if image.ndim == 2:
        image = image[..., None]
    height, width, channels = image.shape
    names = ("R", "G", "B") if channels == 3 else ("Y",)
    if path.endswith(".exr"):
        spec = _spec(width, height, channels, "float", names)
        spec.attribute("compression", "zip")
        data = np.ascontiguousarray(image, np.float32)
    else:
        spec = _spec(width, height, channels, "uint16", names)
        # zlib level 1: a 2048² normal map encodes in 0.39 s instead of 1.22 s (level 6),
        # for files 29% larger (docs/benchmarks.md)
        spec.attribute("png:compressionLevel", PNG_COMPRESSION)
        data = np.ascontiguousarray(np.round(np.clip(image, 0.0, 1.0) * 65535), np.uint16)
    # encoded in memory, then copied and checked: libpng truncates silently on a full disk
    with memory_file(os.path.splitext(path)[1]) as scratch:
        encode_file(scratch, spec, data, final_path)
        copy_complete(scratch, path, atomic=False, shown=final_path)


class MapStaging:
    """Map files encoded into a staging folder beside ``folder``, moved into ``folder``
    by :meth:`commit`; :meth:`discard` (or leaving the ``with`` block by an exception)
    removes them. Staging folders of processes that no longer run are swept."""

    def __init__(self, folder: str):
        self.folder = os.path.abspath(folder)
        parent = os.path.dirname(self.folder)
        self._sweep(parent)
        try:
            os.makedirs(parent, exist_ok=True)
            self.staging = os.path.join(
                parent, f"{STAGING_PREFIX}{os.getpid()}.{os.path.basename(self.folder)}")
            shutil.rmtree(self.staging, ignore_errors=True)
            os.makedirs(self.staging)
        except OSError as exc:
            raise write_error(self.folder, exc) from None
        self.names: list[str] = []

    @staticmethod
    def _sweep(parent: str) -> None:
        sweep_dead(parent, STAGING_PREFIX, lambda path: shutil.rmtree(path, ignore_errors=True))

    def path(self, name: str) -> str:
        """Where a map is encoded; ``name`` is its file name in the map folder."""
        self.names.append(name)
        return os.path.join(self.staging, name)

    def final(self, name: str) -> str:
        return os.path.join(self.folder, name)

    def commit(self) -> None:
        """Move every staged map into the map folder (stop signals held back)."""
        try:
            os.makedirs(self.folder, exist_ok=True)
            with signals_held():
                for name in self.names:
                    os.replace(os.path.join(self.staging, name), self.final(name))
        except OSError as exc:
            raise write_error(self.folder, exc) from None
        self.discard()

    def discard(self) -> None:
        with signals_held():
            shutil.rmtree(self.staging, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        self.discard()
        return False


def relative_asset(path: str, layer_path: str) -> str:
    """``path`` relative to the layer's folder, as an asset path (``./maps/x.png``)."""
    folder = os.path.dirname(os.path.abspath(layer_path))
    relative = os.path.relpath(os.path.abspath(path), folder).replace(os.sep, "/")
    return relative if relative.startswith("../") else "./" + relative


def frame_token(frame: float | None) -> str | None:
    """A frame as it appears in a map's file name, or None for the default time."""
    return None if frame is None else frame_text(frame)
