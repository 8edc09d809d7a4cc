"""Shader loading as moderngl-window does it: #include with a depth limit,
#defines and #line inserted after #version, errors mapped back to file:line.

Shaders are read from the package's ``shaders/`` folder (importlib.resources),
so an installed wheel works as well as a checkout.
"""
from __future__ import annotations

import re
from pathlib import Path

from ..process._resources import resource_dir
from ..process.errors import ShaderError
from ..process.signals import signals_held

MAX_INCLUDE_DEPTH = 8
_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$')
# Mesa: "0:12(3): error: ..."; NVIDIA: "0(12) : error ..."
_ERROR_LINE = re.compile(r"^(\d+):(\d+)\(\d+\)|^(\d+)\((\d+)\)")


class ShaderSource:
    """One preprocessed shader: text plus the table of source-string numbers."""

    def __init__(self, name: str, defines: dict | None = None, root: Path | None = None):
        self.root = root or resource_dir("shaders")
        self.name = name
        self.files: list[str] = []
        path = self.root / name
        if not path.is_file():
            raise ShaderError(name, 0, "shader file not found")
        lines = path.read_text().splitlines()
        if not lines or not lines[0].startswith("#version"):
            raise ShaderError(name, 1, "#version must be on line 1")
        self.version = lines[0]
        self.defines = dict(defines or {})
        self.body = self._expand(name, lines[1:], 2, depth=0, seen=())

    def _file_number(self, name: str) -> int:
        if name not in self.files:
            self.files.append(name)
        return self.files.index(name)

    def _expand(self, name: str, lines: list[str], first_line: int, depth: int, seen) -> str:
        number = self._file_number(name)
        out = [f"#line {first_line} {number}"]
        for offset, line in enumerate(lines):
            match = _INCLUDE.match(line)
            if not match:
                out.append(line)
                continue
            line_no = first_line + offset
            if depth >= MAX_INCLUDE_DEPTH:
                raise ShaderError(name, line_no, f"#include nested deeper than {MAX_INCLUDE_DEPTH}")
            target = match.group(1)
            path = self.root / target
            if not path.is_file():  # then the package's own shaders/ (include/common.glsl)
                path = resource_dir("shaders") / target
            if not path.is_file():
                raise ShaderError(name, line_no, f"#include \"{target}\" not found")
            if target in seen:
                raise ShaderError(name, line_no, f"#include \"{target}\" is recursive")
            out.append(self._expand(target, path.read_text().splitlines(), 1, depth + 1,
                                    seen + (target,)))
            out.append(f"#line {line_no + 1} {number}")
        return "\n".join(out)

    def text(self, stage_define: str | None = None) -> str:
        defines = dict(self.defines)
        if stage_define:
            defines[stage_define] = 1
        header = "\n".join(f"#define {key} {value}" for key, value in defines.items())
        return f"{self.version}\n{header}\n{self.body}\n"

    def map_error(self, message: str) -> ShaderError:
        """Turn a driver's compile log into a ShaderError naming our file and line."""
        for line in message.splitlines():
            match = _ERROR_LINE.match(line.strip())
            if match:
                source = int(match.group(1) or match.group(3))
                line_no = int(match.group(2) or match.group(4))
                name = self.files[source] if source < len(self.files) else self.name
                return ShaderError(name, line_no, line.strip())
        return ShaderError(self.name, 0, message.strip())


class CompiledPrograms:
    """The programs one GL context has compiled, by their full source text: a second
    engine, farm chunk or usdview command in the process compiles none of them again.
    Kept on the context object (``of``), so they go with it; :meth:`release` frees them
    (render/context.release_context does, before it releases the context). A program's
    uniforms keep their values in it, and set_uniforms (render/passes) remembers them on
    the program itself, so engines that share one stay correct."""

    def __init__(self) -> None:
        self.programs: dict[tuple, object] = {}
        #: how many programs this context has compiled (the tests count them)
        self.compiled = 0

    @classmethod
    def of(cls, ctx) -> CompiledPrograms:
        made = getattr(ctx, "_usdwrinkle_programs", None)
        if made is None:
            made = cls()
            ctx._usdwrinkle_programs = made
        return made

    def get(self, key: tuple, make):
        program = self.programs.get(key)
        if program is None or is_released(program):
            # (a caller that released a program it was handed gets a fresh one)
            program = make()
            self.programs[key] = program
            self.compiled += 1
        return program

    def release(self) -> None:
        for program in self.programs.values():
            program.release()
        self.programs.clear()


def is_released(program) -> bool:
    """Whether a moderngl object has been released (its GL object is gone)."""
    return type(program.mglo).__name__ == "InvalidObject"


def release_programs(ctx) -> None:
    """Free every program ``ctx`` compiled (before the context itself goes)."""
    CompiledPrograms.of(ctx).release()


def _compiled(ctx, source: ShaderSource, key: tuple, build):
    """``build()``'s program, compiled once per context for ``key`` (its source texts),
    with the compiler's errors mapped back to ``source``'s files and lines."""
    def make():
        try:
            with signals_held():  # LLVM compiling it (llvmpipe) must not take a signal
                return build()
        except Exception as exc:
            raise source.map_error(str(exc)) from None

    return CompiledPrograms.of(ctx).get(key, make)


def compute_shader(ctx, name: str, defines: dict, root: Path | None = None):
    """A compute shader from ``root`` (default: the package's shaders/), compiled once
    per context (:class:`CompiledPrograms`)."""
    source = ShaderSource(name, defines, root)
    text = source.text()
    return _compiled(ctx, source, ("compute", text), lambda: ctx.compute_shader(text))


def program(ctx, name: str, defines: dict):
    """A vertex+fragment program from one file with VERTEX_SHADER/FRAGMENT_SHADER
    sections, compiled once per context (:class:`CompiledPrograms`)."""
    source = ShaderSource(name, defines)
    vertex, fragment = source.text("VERTEX_SHADER"), source.text("FRAGMENT_SHADER")
    return _compiled(ctx, source, ("program", vertex, fragment),
                     lambda: ctx.program(vertex_shader=vertex, fragment_shader=fragment))


class Variants:
    """The programs of one shader per set of switches (#defines), each compiled on first
    use: ``variants(TWO_SYSTEMS=True, NORMAL_MAP=False)``. A switch that is off is not
    defined, so the common case (the paper's one wave system, no normal map) runs the
    plain code: on llvmpipe, the general code cost a fifth more draw time even when
    unused."""

    def __init__(self, make):
        #: make(extra_defines) -> a program (or a compute shader)
        self.make = make
        self.programs: dict[frozenset, object] = {}

    def __call__(self, **switches: bool):
        key = frozenset(name for name, on in switches.items() if on)
        program = self.programs.get(key)
        if program is None:
            program = self.programs[key] = self.make({name: 1 for name in sorted(key)})
        return program

    def release(self) -> None:
        """Drop the variants: a drawable's vertex array is freed; the programs are the
        context's (:class:`CompiledPrograms`), kept for the next engine."""
        for program in self.programs.values():
            if isinstance(program, DrawableProgram):
                program.release()
        self.programs.clear()


class DrawableProgram:
    """A vertex+fragment program with its attribute-less vertex array (the passes fetch
    their data from tables by gl_VertexID)."""

    def __init__(self, ctx, program):
        self.program = program
        self.vao = ctx.vertex_array(program, [])
        #: the per-frame uniforms last set on it (draw.py)
        self.frame_uniforms: dict | None = None

    def release(self) -> None:
        """Free the vertex array; the program is the context's (CompiledPrograms)."""
        self.vao.release()
