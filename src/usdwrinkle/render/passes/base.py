"""The pass interface: a pass is one file and one shader.

A pass class names its shader (``SHADER``, in the package's shaders/ or in ``ROOT``) and
declares the units it binds (``UNITS``: name -> texture unit for a table it reads, image
unit for one it writes, binding point for a storage buffer; each name is a #define of its
shader) and the tables it owns on each mesh (``TABLES``). Its programs are compiled once
per GL context, per set of switches (``self.variants(TWO_SYSTEMS=True)``).

A **wave pass** (:class:`WavePass`) is a step of the per-mesh compute chain that the
render delegate runs for every frame (skin, normals, crush, relax): ``run(res, step)``.
The chain is the registry's, ordered by ``ORDER``; a new wave pass registers itself with
``@wave_pass`` (docs/architecture.md, "A new wave pass", shows the smallest real one,
tests/passes/motion.py).
"""
from __future__ import annotations

import contextlib
import functools
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

from .. import bindings
from ..shaders import DrawableProgram, Variants, compute_shader, program
from . import bind, groups, set_uniforms


@dataclass(frozen=True)
class TableSpec:
    """A table a pass owns on each mesh: ``components`` (1, 2 or 4) values of ``dtype``
    ("f4" or "i4") per point, triangle or triangle corner (``per``)."""

    per: str
    components: int = 4
    dtype: str = "f4"

    def count(self, res: Any) -> int:
        if self.per == "point":
            return int(res.num_points)
        if self.per == "triangle":
            return int(res.num_triangles)
        if self.per == "corner":
            return 3 * int(res.num_triangles)
        raise ValueError(f"a table is per point, triangle or corner, not {self.per!r}")


class Pass:
    """A compute pass: its shader, its units, its tables (see the module)."""

    #: the shader file
    SHADER: ClassVar[str]
    #: where SHADER lives (None: the package's shaders/); its #includes fall back to the
    #: package's (include/common.glsl)
    ROOT: ClassVar[Path | None] = None
    #: name -> unit: the #defines its shader binds its tables and buffers by
    UNITS: ClassVar[dict[str, int]] = {}
    #: name -> the table it owns on each mesh (``self.table(res, name)``)
    TABLES: ClassVar[dict[str, TableSpec]] = {}

    def __init__(self, ctx: Any):
        self.ctx = ctx
        self.variants = Variants(self._compile)

    def defines(self, extra: dict) -> dict:
        return {**bindings.COMMON, **self.UNITS, **extra}

    def _compile(self, extra: dict) -> Any:
        return compute_shader(self.ctx, self.SHADER, self.defines(extra), self.ROOT)

    def bind(self, reads: dict | None = None, writes: dict | None = None,
             read_writes: dict | None = None, storage: dict | None = None) -> None:
        """Bind tables and buffers to this pass's UNITS (passes.bind)."""
        bind(self.UNITS, reads, writes, read_writes, storage)

    def dispatch(self, count: int, uniforms: dict, reads: dict | None = None,
                 writes: dict | None = None, read_writes: dict | None = None,
                 storage: dict | None = None, **switches: bool) -> None:
        """Run the variant of ``switches`` over ``count`` elements (one invocation each,
        in work groups of LOCAL_SIZE), with ``uniforms`` set and the tables bound; then a
        memory barrier, so that the next pass reads what this one wrote."""
        shader = self.variants(**switches)
        set_uniforms(shader, uniforms)
        self.bind(reads, writes, read_writes, storage)
        shader.run(groups(count, bindings.LOCAL_SIZE))
        self.ctx.memory_barrier()

    @classmethod
    def table(cls, res: Any, name: str) -> Any:
        """The table ``name`` of TABLES that this pass owns on the mesh ``res``
        (render/resources.MeshResources; made on first use, released with the mesh's
        other tables)."""
        return res.owned_table(f"{cls.__module__}.{cls.__qualname__}.{name}",
                               cls.TABLES[name])

    def release(self) -> None:
        """Free what this pass made (a drawn pass's vertex arrays); the programs are the
        context's (render/shaders.CompiledPrograms), kept for the next engine."""
        self.variants.release()


class DrawnPass(Pass):
    """A pass that rasterises (a vertex and fragment program from one file with
    VERTEX_SHADER and FRAGMENT_SHADER sections): the maps' UV-space blend."""

    def _compile(self, extra: dict) -> Any:
        return DrawableProgram(self.ctx, program(self.ctx, self.SHADER, self.defines(extra)))


@dataclass(frozen=True)
class Step:
    """What one mesh's compute chain knows about the frame it computes."""

    #: the mesh's synced frame (scene/records.MeshFrame)
    frame: Any
    #: False: the same shading without wrinkles (the waves' amplitude 0)
    wrinkles: bool
    #: the wave state of the shot's previous grid frame is read (crest damping, relax's
    #: seed); False: a cold start
    history: bool
    #: relaxation steps (wrinkle:relaxIterations, longer on a cold start; 0: none)
    iterations: int
    #: the frame's baked wave fields (scene/baked.BakedFields), drawn instead of computed;
    #: None: computed
    baked: Any = None
    #: False: a preroll step, computed for the phase history alone and never drawn (the
    #: passes whose results only the outputs read leave it out: the length pass)
    drawn: bool = True


class WavePass(Pass):
    """A step of the per-mesh compute chain (module docstring)."""

    #: the render --stats entry its time adds to
    TIMING: ClassVar[str]
    #: its place in the chain (skin 10, normals 20, crush 30, relax 40, length 50)
    ORDER: ClassVar[float]

    def run(self, res: Any, step: Step) -> None:
        raise NotImplementedError


_REGISTRY: list[type[WavePass]] = []


def wave_pass(cls: type[WavePass]) -> type[WavePass]:
    """Register a wave pass (a class decorator): every render delegate made afterwards
    runs it, at its ORDER."""
    if cls not in _REGISTRY:
        _REGISTRY.append(cls)
    return cls


@functools.cache
def _discover() -> None:
    """Import every module of this folder once, so that each pass file registers its
    passes: a new wave pass is one file here, and no list elsewhere names it."""
    import importlib
    import pkgutil

    package = __name__.rsplit(".", 1)[0]
    for info in pkgutil.iter_modules([str(Path(__file__).parent)]):
        if info.name != "base":
            importlib.import_module(f"{package}.{info.name}")


def wave_passes() -> list[type[WavePass]]:
    """The registered wave passes, in the order they run: those of this folder's files,
    and those registered by a caller (``registered``)."""
    _discover()
    return sorted(_REGISTRY, key=lambda cls: cls.ORDER)


@contextlib.contextmanager
def registered(*classes: type[WavePass]) -> Iterator[None]:
    """Wave passes registered for the block only (a test's, an experiment's)."""
    added = [cls for cls in classes if cls not in _REGISTRY]
    _REGISTRY.extend(added)
    try:
        yield
    finally:
        for cls in added:
            _REGISTRY.remove(cls)
