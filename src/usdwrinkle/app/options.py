"""The options of each job, typed and documented: what every door fills in.

A field is named as the command line's option is, with ``_`` for ``-`` (``width`` is
``--width``, ``map_size`` is ``--map-size``). Messages name a field in backquotes
(`` `width` ``): a Python caller reads the field, the command line prints its flag
instead (cli/flags.py). Each dataclass checks its
values when it is made: a value of the wrong type, or outside its choices, raises
:class:`usdwrinkle.process.errors.UsdWrinkleError` naming the field. Ranges that need no stage
are checked by ``check()``; what needs the stage or the GL context, by the job.
"""
from __future__ import annotations

import dataclasses
import os
import typing
from dataclasses import dataclass

from ..geometry.options import GeometryOptions
from ..images.aovs import AOVS_TEXT  # noqa: F401  (re-exported: what render --help lists)
from ..maps.options import LAYOUTS as MAP_LAYOUTS
from ..maps.options import TANGENT_SPACES, MapOptions
from ..outputs.images import EXR_COMPRESSIONS
from ..outputs.writer import MAX_THREADS as MAX_WRITE_THREADS
from ..process.errors import UsdWrinkleError
from ..render.resolve import MAX_RING
from ..usd.schema import MAP_ST, baked_names_text

#: what --help shows of the defaults and names below
MAP_DEFAULTS = MapOptions()
GEOMETRY_DEFAULTS = GeometryOptions()
BAKED_NAMES_TEXT = baked_names_text()
MAP_ST_NAME = MAP_ST
DISPLAY_COLORS = ("amplitude", "compression")
MAP_FORMATS = ("png", "exr")


def _kind(hint: typing.Any) -> tuple[typing.Any, bool, bool]:
    """(the base type, None allowed, a tuple of it) of a field's annotation."""
    import types

    union = typing.get_origin(hint) in (typing.Union, types.UnionType)
    members = typing.get_args(hint) if union else (hint,)
    optional = type(None) in members
    inner = [a for a in members if a is not type(None)][0]
    if typing.get_origin(inner) is tuple:
        return typing.get_args(inner)[0], optional, True
    return inner, optional, False


def _checked_value(name: str, value: typing.Any, base: typing.Any) -> typing.Any:
    """``value`` as a field of type ``base`` takes it, or UsdWrinkleError naming ``name``."""
    if base is bool:
        if not isinstance(value, bool):
            raise UsdWrinkleError(f"`{name}`={value!r} must be True or False")
        return value
    if base in (int, float):
        import numbers

        # numpy's numbers too (np.int64(32) is an integer); never a bool or a text
        number = isinstance(value, numbers.Real) and not isinstance(value, bool) and \
            type(value).__name__ != "bool_"
        if number and base is int and not float(value).is_integer():
            number = False
        if not number:
            raise UsdWrinkleError(f"`{name}`={value!r} must be "
                                  f"{'an integer' if base is int else 'a number'}")
        return base(value)
    if base is str:
        if isinstance(value, os.PathLike):
            value = os.fspath(value)
        if not isinstance(value, str):
            raise UsdWrinkleError(f"`{name}`={value!r} must be a string")
        return value
    return value


class _Checked:
    """Type and choice checks of a frozen dataclass's fields, when it is made."""

    #: field -> the values it may take
    CHOICES: typing.ClassVar[dict[str, tuple[str, ...]]] = {}

    def __post_init__(self) -> None:
        hints = typing.get_type_hints(type(self))
        for field in dataclasses.fields(self):  # type: ignore[arg-type]
            value = getattr(self, field.name)
            base, optional, many = _kind(hints[field.name])
            if value is None:
                if not optional:
                    raise UsdWrinkleError(f"`{field.name}` must be given")
                continue
            if many:
                if isinstance(value, (str, os.PathLike)):
                    value = (value,)
                try:
                    items = tuple(value)
                except TypeError:
                    raise UsdWrinkleError(f"`{field.name}`={value!r} must be a list") from None
                value = tuple(_checked_value(field.name, item, base) for item in items)
            else:
                value = _checked_value(field.name, value, base)
            choices = self.CHOICES.get(field.name)
            if choices is not None and value not in choices:
                raise UsdWrinkleError(f"`{field.name}`={value!r} is not one of "
                                      f"{', '.join(map(str, choices))}")
            object.__setattr__(self, field.name, value)


@dataclass(frozen=True)
class ShotOptions(_Checked):
    """How a shot is opened and its wrinkles computed (render and bake alike)."""

    #: wrinkle every Mesh, as if WrinkleAPI were applied (with its fallbacks)
    all_meshes: bool = False
    #: phase relaxation iterations per frame, 0..10,000 (None: wrinkle:relaxIterations)
    relax_iterations: int | None = None
    #: the first frame of the shot's phase history (None: the stage's start time code)
    history_start: float | None = None
    #: layers over the stage, strongest first (scene/composition.py)
    sublayer: tuple[str, ...] = ()
    #: variant selections, each "/Prim{set=name}"
    variant: tuple[str, ...] = ()
    #: prim paths: the stage is opened with a population mask of them
    mask: tuple[str, ...] = ()

    def check(self) -> None:
        from ..process.limits import MAX_RELAX_ITERATIONS
        from .frames import check_time_code

        if self.relax_iterations is not None and \
                not 0 <= self.relax_iterations <= MAX_RELAX_ITERATIONS:
            raise UsdWrinkleError(f"`relax_iterations` must be in 0..{MAX_RELAX_ITERATIONS:,}")
        if self.history_start is not None:
            check_time_code(self.history_start, "`history_start`")

    def composition(self) -> typing.Any:
        """The scene/composition.Composition of these options (empty without them)."""
        from ..scene.composition import Composition

        mask = [part.strip() for text in self.mask for part in text.split(",")
                if part.strip()]
        return Composition(tuple(self.sublayer), tuple(self.variant), tuple(mask))


@dataclass(frozen=True)
class RenderOptions(_Checked):
    """How a render draws and writes its frames (``usdwrinkle render --help``)."""

    CHOICES: typing.ClassVar[dict[str, tuple[str, ...]]] = {"exr_compression": EXR_COMPRESSIONS}

    #: camera prim path or name (None: the primary camera, the first camera, or an
    #: automatic framing of the bounds)
    camera: str | None = None
    width: int = 960
    #: None: from the camera's aspect ratio
    height: int | None = None
    #: multisamples per pixel, a power of two
    samples: int = 4
    #: where folds turn within a pixel, shade each multisample where it lies (False:
    #: every pixel once, at its centroid)
    shade_samples: bool = True
    #: draw the folds where the view ray meets them (flanks that face away hide behind
    #: the crests, as on the displaced geometry), not where it meets the coarse surface
    relief: bool = False
    #: threads that encode and write frames while the next ones render, 0..64 (None: every
    #: core but one; 0: each frame is written before the next renders)
    write_threads: int | None = None
    #: GPU readback buffers, 1..8: frame f is copied out while the next frames compute
    #: (1: each frame is read back as soon as it is drawn; None: 3 on a GPU, 1 on llvmpipe)
    readback_buffers: int | None = None
    #: EXR: colour and normals as half float (depth and the wrinkle fields stay float)
    exr_half: bool = True
    exr_compression: str = "zip"
    #: EXR: the AOVs each frame stores, aovs.AOV_BLOCKS' names (a comma-separated text or a
    #: list; None: every one). An 8-bit frame stores the colour alone
    aovs: tuple[str, ...] | None = None
    #: the same shading without wrinkles
    no_wrinkles: bool = False
    #: leave frames whose file is already a whole image of this size
    skip_existing: bool = False
    #: ignore baked wave fields in the stage and compute every mesh's wrinkles
    recompute: bool = False
    #: a JSON file for per-frame timings (each pass timed, with glFinish between passes)
    stats: str | None = None
    #: with ``stats``: time each pass (False: the frame loop's times alone, the GPU
    #: working ahead as without ``stats``)
    stats_passes: bool = True
    #: render on Dask (farm/): "local" (a local cluster) or a scheduler's address; None
    #: renders here
    dask: str | None = None
    #: with ``dask`` "local": worker processes (None: one per core)
    workers: int | None = None
    #: with ``dask``: frames per task (None: at most 10, two chunks per worker or more)
    chunk: int | None = None

    def __post_init__(self) -> None:
        if self.dask is not None and not isinstance(self.dask, str):
            raise UsdWrinkleError(f"`dask`={self.dask!r} must be 'local' or a scheduler's "
                                  "address")
        super().__post_init__()

    def check(self) -> None:
        from ..farm.client import check_farm_options
        from ..render.buffers import check_samples

        check_farm_options(self.dask, self.workers, self.chunk)

        if self.width <= 0 or (self.height is not None and self.height <= 0):
            raise UsdWrinkleError("`width` and `height` must be positive")
        check_samples(self.samples)
        if self.write_threads is not None and \
                not 0 <= self.write_threads <= MAX_WRITE_THREADS:
            raise UsdWrinkleError(f"`write_threads` must be in 0..{MAX_WRITE_THREADS}")
        if self.readback_buffers is not None and not 1 <= self.readback_buffers <= MAX_RING:
            raise UsdWrinkleError(f"`readback_buffers` must be in 1..{MAX_RING}")
        self.chosen_aovs()

    def chosen_aovs(self, path: str | None = None) -> tuple[str, ...]:
        """The AOVs each frame stores, in aovs.AOV_BLOCKS order (refuses unknown names);
        with the output ``path``: for an 8-bit file the colour, and only the colour."""
        from ..images.aovs import AOV_BLOCKS, parse_aovs
        from ..outputs.images import stored_aovs

        aovs = None if self.aovs is None else parse_aovs(self.aovs)
        if path is None:
            return AOV_BLOCKS if aovs is None else aovs
        return stored_aovs(path, aovs)

    def frame_request(self, width: int, height: int, path: str) -> typing.Any:
        """The render/request.FrameRequest of each frame written to ``path`` (its format
        sets the layout read back), at the resolved ``width`` x ``height``."""
        from ..outputs.images import layout_for
        from ..render.request import FrameRequest

        return FrameRequest(width, height, self.samples, not self.no_wrinkles,
                            self.shade_samples, self.relief,
                            layout_for(path, self.exr_half, self.chosen_aovs(path)),
                            self.readback_buffers)


@dataclass(frozen=True)
class BakeOptions(_Checked):
    """What a bake writes besides the wrinkle primvars (``usdwrinkle bake --help``)."""

    CHOICES: typing.ClassVar[dict[str, tuple[str, ...]]] = {
        "display_color": DISPLAY_COLORS, "map_format": MAP_FORMATS,
        "tangent_space": TANGENT_SPACES, "map_layout": MAP_LAYOUTS}

    #: also the posed points and extent (and normals where the mesh authors them)
    with_points: bool = False
    #: also primvars:displayColor as a viridis ramp of this field
    display_color: str | None = None
    #: the overs alone, without sublayering the input
    sparse: bool = False
    #: wrinkle maps: "normal", "height", "amplitude" (a comma-separated text or a list)
    maps: tuple[str, ...] | None = None
    map_size: int | None = None
    map_dir: str | None = None
    map_format: str | None = None
    map_padding: int | None = None
    map_layout: str | None = None
    uv: str | None = None
    tangent_space: str | None = None
    map_displacement: bool | None = None
    #: a displaced render mesh per wrinkled mesh, the coarse mesh its proxy
    geometry: bool = False
    levels: int | None = None
    samples_per_wavelength: float | None = None


#: BakeOptions field -> maps/options.MapOptions field
MAP_FIELDS = {"map_size": "size", "map_dir": "folder", "map_format": "fmt",
              "map_padding": "padding", "uv": "uv", "tangent_space": "tangent_space",
              "map_layout": "layout", "map_displacement": "displacement"}
#: BakeOptions field -> geometry/options.GeometryOptions field
GEOMETRY_FIELDS = {"levels": "levels", "samples_per_wavelength": "samples_per_wavelength"}


@dataclass(frozen=True)
class ApplyOptions:
    """What ``usdwrinkle apply`` authors (its --help says what each field does)."""

    stage: str
    prim_paths: tuple[str, ...]
    output: str | None = None
    width: float | None = None
    cloth: str | None = None
    slack: float | None = None
    crest_damping: float | None = None
    irregularity: float | None = None
    held_from_primvar: str | None = None
    amplitude_scale: float | None = None
    biaxial: float | None = None
    tension: float | None = None
    tension_threshold: float | None = None
    profile: str | None = None
    q: str | None = None
    q_from_texture: str | None = None
    uv: str = "st"
    amount_channel: str | None = None
    q_from_primvar: str | None = None
    width_from_texture: str | None = None
    clear_q: bool = False
