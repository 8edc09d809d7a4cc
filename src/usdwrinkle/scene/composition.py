"""Composition options: open a shot as a pipeline composes it, without a shot file.

What usdview and usdrecord take as options, and what a TD would otherwise write a shot
file for (issue 44):

- ``sublayers``: layers over the stage, strongest first (an override layer over a
  read-only ``.usdz``: units, WrinkleAPI values, a fixed camera);
- ``variants``: variant selections, each in USD's path syntax ``/Prim{set=name}``;
- ``mask``: prim paths; the stage is opened with a population mask of them (and what
  they need: their ancestors, and the targets of their relationships are not loaded
  unless also named, as in usdview's ``--mask``).

They go into an anonymous session layer, so the stage's own files are never changed. A
bake records the sublayers and variant selections in its layer (outputs/layers.py), so
that the layer renders as the composed stage did.
"""
from __future__ import annotations

from dataclasses import dataclass

from pxr import Sdf, Usd

from ..process.errors import UsdWrinkleError

#: customLayerData key of the session layer that holds a Composition (a bake reads it)
SESSION_KEY = "usdwrinkleComposition"


@dataclass(frozen=True)
class Composition:
    sublayers: tuple = ()
    variants: tuple = ()
    mask: tuple = ()

    def __bool__(self) -> bool:
        return bool(self.sublayers or self.variants or self.mask)

    def selections(self) -> list[tuple[str, str, str]]:
        """(prim path, variant set, variant name) of each variant selection."""
        return [parse_variant(text) for text in self.variants]


def parse_variant(text: str) -> tuple[str, str, str]:
    """``/Prim{set=name}`` -> ("/Prim", "set", "name"), or a one-line error."""
    valid, _why = Sdf.Path.IsValidPathString(text)
    path = Sdf.Path(text) if valid else None
    if path is None or not path.ContainsPrimVariantSelection() or \
            not path.IsPrimVariantSelectionPath():
        raise UsdWrinkleError(f"variant selection '{text}' must be a prim path with one "
                              "selection, /Prim{set=name} (USD's variant path syntax)")
    variant_set, name = path.GetVariantSelection()
    if not name:
        raise UsdWrinkleError(f"variant selection '{text}' names no variant of set "
                              f"'{variant_set}'")
    return str(path.StripAllVariantSelections()), variant_set, name


def session_layer(composition: Composition, anchor: str) -> Sdf.Layer:
    """The anonymous session layer that holds ``composition`` (sublayer paths absolute:
    relative ones are taken from the current folder, as on a command line)."""
    import os

    from .inputs import open_layer, require_regular_file

    layer = Sdf.Layer.CreateAnonymous("usdwrinkle-composition.usda")
    paths = []
    for path in composition.sublayers:
        absolute = os.path.abspath(path)
        if not os.path.exists(absolute):
            raise UsdWrinkleError(f"sublayer '{path}' does not exist")
        require_regular_file(absolute, "sublayer")
        open_layer(absolute, f"cannot open '{path}' as a USD layer")
        if os.path.realpath(absolute) == os.path.realpath(anchor):
            raise UsdWrinkleError(f"sublayer '{path}' is the stage itself")
        paths.append(absolute)
    layer.subLayerPaths = paths
    for prim_path, variant_set, name in composition.selections():
        spec = Sdf.CreatePrimInLayer(layer, prim_path)
        spec.specifier = Sdf.SpecifierOver
        spec.variantSelections[variant_set] = name
    layer.customLayerData = {SESSION_KEY: {
        "sublayers": list(paths), "variants": list(composition.variants)}}
    return layer


def population_mask(composition: Composition) -> Usd.StagePopulationMask | None:
    if not composition.mask:
        return None
    mask = Usd.StagePopulationMask()
    for text in composition.mask:
        valid, why = Sdf.Path.IsValidPathString(text)
        if not valid or not Sdf.Path(text).IsAbsoluteRootOrPrimPath() or \
                not Sdf.Path(text).IsAbsolutePath():
            raise UsdWrinkleError(f"mask '{text}' is not an absolute prim path"
                                  + (f" ({why.rstrip('.')})" if why else ""))
        mask.Add(Sdf.Path(text))
    return mask


def check_composed(stage: Usd.Stage, composition: Composition) -> None:
    """Refuse a variant selection or a mask that selects nothing, naming what there is."""
    for prim_path, variant_set, name in composition.selections():
        prim = stage.GetPrimAtPath(prim_path)
        session = stage.GetSessionLayer()
        if not prim or all(spec.layer == session for spec in prim.GetPrimStack()):
            raise UsdWrinkleError(f"variant selection: no prim {prim_path} on the stage")
        sets = prim.GetVariantSets()
        if not sets.HasVariantSet(variant_set):
            known = ", ".join(sets.GetNames()) or "none"
            raise UsdWrinkleError(f"variant selection: {prim_path} has no variant set "
                                  f"'{variant_set}' (its sets: {known})")
        names = sets.GetVariantSet(variant_set).GetVariantNames()
        if name not in names:
            raise UsdWrinkleError(f"variant selection: set '{variant_set}' of {prim_path} "
                                  f"has no variant '{name}' (its variants: "
                                  f"{', '.join(names) or 'none'})")
    for text in composition.mask:
        if not stage.GetPrimAtPath(text):
            raise UsdWrinkleError(f"mask '{text}' names no prim of the stage")


def recorded(stage: Usd.Stage) -> tuple[list[str], list[tuple[str, str, str]]]:
    """(sublayers, variant selections) of the Composition the stage was opened with (the
    session layer open_stage made), or empty lists."""
    session = stage.GetSessionLayer()
    data = session.customLayerData.get(SESSION_KEY) if session else None
    if not data:
        return [], []
    return list(data.get("sublayers", [])), [parse_variant(text)
                                             for text in data.get("variants", [])]
