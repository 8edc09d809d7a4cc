"""Every file a stage reads, found before USD opens any of it.

:func:`scan_inputs` walks the layer stack from the root layer by hand: sublayers,
references and payloads (in every variant, selected or not), and asset-valued
attributes (textures). It checks that each existing file is a regular file *before* it
is opened, so that a FIFO or a device never blocks a run, and opens each layer once,
with USD's errors turned into one line that keeps a syntax error's file:line. The
layers stay open, so ``Usd.Stage.Open`` then reads nothing twice.

The result also says what no output may overwrite: the real path and inode of every
input that exists, and the path of every input that does not exist yet (a sublayer
that a bake onto it would turn into a cycle).
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field

from pxr import Ar, Sdf, Tf, UsdUtils

from ..process.errors import UsdWrinkleError
from ..usd.diagnostics import usd_diagnostics, usd_error_text


def package_file(resolved: str) -> str:
    """The file on disk behind a resolved path: 'a.usdz[b/c.png]' -> 'a.usdz'."""
    if resolved.endswith("]") and "[" in resolved:
        return resolved[:resolved.index("[")]
    return resolved


def require_regular_file(path: str, what: str, used_by: str | None = None) -> None:
    """Refuse a path that exists but is not a regular file (a FIFO, a device, a folder):
    reading it could block forever or never end."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return  # missing: the caller's own message says so
    if not stat.S_ISREG(mode):
        kind = "a folder" if stat.S_ISDIR(mode) else \
            "a FIFO" if stat.S_ISFIFO(mode) else \
            "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else \
            "a socket" if stat.S_ISSOCK(mode) else "not a regular file"
        where = f" (used by '{used_by}')" if used_by else ""
        raise UsdWrinkleError(f"{what} '{path}'{where} is {kind}, not a regular file")


@dataclass
class StageInputs:
    """What a stage reads. ``layers`` keeps its layers open."""

    layers: list = field(default_factory=list)
    #: real paths of every input file that exists (layers, packages, textures)
    files: set = field(default_factory=set)
    #: (st_dev, st_ino) of those files: a hard link to an input is an input
    inodes: set = field(default_factory=set)
    #: absolute paths of inputs that do not exist yet (missing sublayers, textures)
    missing: set = field(default_factory=set)

    def add_file(self, path: str) -> None:
        real = os.path.realpath(path)
        self.files.add(real)
        try:
            st = os.stat(real)
            self.inodes.add((st.st_dev, st.st_ino))
        except OSError:
            pass

    def protects(self, output: str) -> bool:
        """True when writing ``output`` would write over (or into) an input."""
        real = os.path.realpath(output)
        if real in self.files or real in self.missing:
            return True
        try:
            st = os.stat(real)
        except OSError:
            return False
        return (st.st_dev, st.st_ino) in self.inodes


def open_layer(identifier: str, what: str, required: bool = True):
    """Sdf.Layer.FindOrOpen with USD's errors as one line after ``what`` (a syntax error
    keeps its file:line); a layer that cannot be opened is an error when ``required``,
    else None (USD then warns about it when the stage is composed)."""
    try:
        with usd_diagnostics() as messages:
            layer = Sdf.Layer.FindOrOpen(identifier)
    except Tf.ErrorException as exc:
        raise UsdWrinkleError(f"{what}: {usd_error_text(exc)}") from None
    if layer is None and required:
        detail = f": {messages[-1]}" if messages else ""
        raise UsdWrinkleError(f"{what}{detail}")
    return layer


def _would_resolve_to(layer, asset: str, absolute: str) -> set[str]:
    """Where an asset that does not exist yet would be found once a file appears there:
    the real paths an output must not take. A search path (``@later.usda@``, neither
    anchored nor absolute) is looked up beside the layer first, then in the default
    resolver's search path (PXR_AR_DEFAULT_SEARCH_PATH); ComputeAbsolutePath leaves it
    bare when nothing is found, so it is anchored here, never at the working folder."""
    if not absolute or "[" in absolute:
        return set()
    if os.path.isabs(absolute):
        return {os.path.realpath(absolute)}
    folders = [os.path.dirname(layer.realPath)] if layer.realPath else []
    folders += [folder for folder in os.environ.get("PXR_AR_DEFAULT_SEARCH_PATH", "")
                .split(os.pathsep) if folder]
    return {os.path.realpath(os.path.join(folder, absolute)) for folder in folders}


def scan_inputs(stage_path: str) -> StageInputs:
    """Open the stage's layers (not the stage) and list every file it reads."""
    inputs = StageInputs()
    require_regular_file(stage_path, "stage")
    root = open_layer(os.path.abspath(stage_path),
                      f"cannot open '{os.path.abspath(stage_path)}' as a USD stage")
    inputs.layers.append(root)
    inputs.add_file(stage_path)
    if root.realPath:
        inputs.add_file(package_file(root.realPath))
    seen = {root.identifier}
    queue = [root]
    resolver = Ar.GetResolver()
    while queue:
        layer = queue.pop()
        if layer.anonymous:
            continue
        with usd_diagnostics():
            sublayers, references, payloads = UsdUtils.ExtractExternalReferences(
                layer.identifier)
        for asset in (*sublayers, *references, *payloads):
            if not asset or asset.startswith("anon:"):
                continue
            absolute = layer.ComputeAbsolutePath(asset)
            resolved = str(resolver.Resolve(absolute)) if absolute else ""
            if not resolved:
                inputs.missing.update(_would_resolve_to(layer, asset, absolute))
                continue
            disk = package_file(resolved)
            require_regular_file(disk, "input", layer.identifier)
            inputs.add_file(disk)
            extension = os.path.splitext(package_file(asset))[1].lstrip(".")
            is_layer = asset in sublayers or asset in payloads or \
                Sdf.FileFormat.FindByExtension(extension) is not None
            if is_layer and resolved not in seen:
                seen.add(resolved)
                child = open_layer(resolved, f"cannot read layer '{disk}' (used by "
                                             f"'{layer.identifier}')", required=False)
                if child is not None:
                    seen.add(child.identifier)
                    inputs.layers.append(child)
                    queue.append(child)
    return inputs
