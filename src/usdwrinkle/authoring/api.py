"""``usdwrinkle.WrinkleAPI``: what a generated schema class would be, in Python.

    from usdwrinkle import WrinkleAPI
    api = WrinkleAPI.Apply(mesh_prim)
    api.CreateWidthPrimvar([0.05])
    api.set_q(q_array)

Names follow USD's generated code (``Get…Attr``/``Create…Attr``; primvars as
``Get…Primvar``/``Create…Primvar``). Every write is checked with the rules of
``usdwrinkle check`` and refused with a UsdWrinkleError before anything is set.
"""
from __future__ import annotations

import numpy as np
from pxr import Sdf, Usd, UsdGeom, Vt

from ..method.profiles import derive_gradient
from ..process.errors import UsdWrinkleError
from ..usd import schema
from ..usd.validation import (
    check_amplitude_scale,
    check_biaxial,
    check_cloth,
    check_crest_damping,
    check_held,
    check_irregularity,
    check_profile,
    check_q,
    check_relax_iterations,
    check_slack,
    check_tension,
    check_tension_threshold,
    check_width,
    point_count,
    refuse,
)
from ..usd.values import flattened


class WrinkleAPI:
    """Single-apply API schema for Mesh prims (codeless: this class wraps the prim)."""

    schemaName = schema.API_NAME

    def __init__(self, prim: Usd.Prim | None = None):
        if isinstance(prim, WrinkleAPI):
            prim = prim.GetPrim()
        self._prim = prim if prim is not None else Usd.Prim()

    # -- schema plumbing ------------------------------------------------------------
    def GetPrim(self) -> Usd.Prim:  # noqa: N802 (USD naming)
        return self._prim

    def GetPath(self) -> Sdf.Path:  # noqa: N802
        return self._prim.GetPath()

    def __bool__(self) -> bool:
        return bool(self._prim) and schema.has_wrinkle_api(self._prim)

    def __repr__(self) -> str:
        return f"usdwrinkle.WrinkleAPI({self._prim!r})"

    @classmethod
    def Get(cls, stage: Usd.Stage, path) -> WrinkleAPI:  # noqa: N802
        return cls(stage.GetPrimAtPath(Sdf.Path(str(path))))

    @staticmethod
    def CanApply(prim: Usd.Prim) -> bool:  # noqa: N802
        schema.require_schema()
        result = prim.CanApplyAPI(schema.API_NAME)
        return bool(result[0] if isinstance(result, tuple) else result)

    @classmethod
    def Apply(cls, prim: Usd.Prim) -> WrinkleAPI:  # noqa: N802
        """Apply WrinkleAPI to a Mesh; raises UsdWrinkleError on any other prim."""
        schema.require_schema()
        if not prim or not prim.IsA(UsdGeom.Mesh):
            kind = prim.GetTypeName() if prim else "missing"
            raise UsdWrinkleError(f"WrinkleAPI applies to Mesh prims, not to a {kind or 'typeless'}"
                                  " prim", str(prim.GetPath()) if prim else None)
        if not prim.ApplyAPI(schema.API_NAME):
            raise UsdWrinkleError("cannot apply WrinkleAPI", str(prim.GetPath()))
        return cls(prim)

    @staticmethod
    def GetSchemaAttributeNames(includeInherited: bool = True) -> list[str]:  # noqa: N802, N803
        return [schema.Q, schema.WIDTH, schema.AMPLITUDE_SCALE, schema.HEIGHT_PROFILE,
                schema.GRADIENT_PROFILE, schema.RELAX_ITERATIONS, schema.BIAXIAL,
                schema.TENSION, schema.TENSION_THRESHOLD, schema.CLOTH, schema.SLACK,
                schema.HELD, schema.CREST_DAMPING]

    # -- attributes -------------------------------------------------------------------
    def _primvars(self) -> UsdGeom.PrimvarsAPI:
        return UsdGeom.PrimvarsAPI(self._prim)

    def _path(self) -> str:
        return str(self._prim.GetPath())

    def _point_count(self) -> int | None:
        return point_count(self._prim)

    def GetQPrimvar(self) -> UsdGeom.Primvar:  # noqa: N802
        return self._primvars().GetPrimvar("wrinkle:q")

    def CreateQPrimvar(self, default_value=None) -> UsdGeom.Primvar:  # noqa: N802
        primvar = self._primvars().CreatePrimvar("wrinkle:q", Sdf.ValueTypeNames.Vector3fArray,
                                                 UsdGeom.Tokens.vertex)
        if default_value is not None:
            self.set_q(default_value)
        return primvar

    def GetWidthPrimvar(self) -> UsdGeom.Primvar:  # noqa: N802
        return self._primvars().GetPrimvar("wrinkle:width")

    def CreateWidthPrimvar(self, default_value=None, time=Usd.TimeCode.Default()):  # noqa: N802, B008
        """Constant for one value, vertex interpolation for one value per point."""
        return self._float_primvar("wrinkle:width", default_value, check_width,
                                   UsdGeom.Tokens.constant, time)

    def _float_primvar(self, name: str, default_value, check, unset_interpolation,
                       time=Usd.TimeCode.Default()):  # noqa: B008
        """A float[] primvar: constant for one value, vertex for one per point (without a
        value, ``unset_interpolation``); the value refused by ``check`` first."""
        values = None if default_value is None else np.atleast_1d(
            np.asarray(default_value, np.float32))
        if values is None:
            interpolation = unset_interpolation
        else:
            interpolation = UsdGeom.Tokens.constant if values.size == 1 \
                else UsdGeom.Tokens.vertex
            refuse(check(values, self._point_count(), self._path()))
        primvar = self._primvars().CreatePrimvar(name, Sdf.ValueTypeNames.FloatArray,
                                                 interpolation)
        primvar.SetInterpolation(interpolation)
        if values is not None:
            primvar.Set(Vt.FloatArray.FromNumpy(values), time)
        return primvar

    def _attr(self, name):
        return self._prim.GetAttribute(name)

    def _create(self, name, type_name, value, check=None):
        if value is not None and check is not None:
            refuse(check(value))
        attr = self._prim.CreateAttribute(name, type_name)
        if value is not None:
            attr.Set(value)
        return attr

    def GetAmplitudeScaleAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.AMPLITUDE_SCALE)

    def CreateAmplitudeScaleAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create(schema.AMPLITUDE_SCALE, Sdf.ValueTypeNames.Float,
                            None if default_value is None else float(default_value),
                            lambda v: check_amplitude_scale(v, self._path()))

    def GetClothAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.CLOTH)

    def CreateClothAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create(schema.CLOTH, Sdf.ValueTypeNames.Token, default_value,
                            lambda v: check_cloth(v, self._path()))

    def GetSlackAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.SLACK)

    def CreateSlackAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create(schema.SLACK, Sdf.ValueTypeNames.Float, default_value,
                            lambda v: check_slack(v, self._path()))

    def GetCrestDampingAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.CREST_DAMPING)

    def CreateCrestDampingAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create(schema.CREST_DAMPING, Sdf.ValueTypeNames.Float, default_value,
                            lambda v: check_crest_damping(v, self._path()))

    def GetIrregularityAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.IRREGULARITY)

    def CreateIrregularityAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create(schema.IRREGULARITY, Sdf.ValueTypeNames.Float, default_value,
                            lambda v: check_irregularity(v, self._path()))

    def GetHeldPrimvar(self) -> UsdGeom.Primvar:  # noqa: N802
        return self._primvars().GetPrimvar("wrinkle:held")

    def CreateHeldPrimvar(self, default_value=None) -> UsdGeom.Primvar:  # noqa: N802
        """One weight in [0, 1] per point (vertex), or one for every point (constant). An
        edge of the mesh with both ends held damps the waves around it; a held point on
        no held edge is a pin and damps nothing (docs/method.md, "Held edges")."""
        return self._float_primvar("wrinkle:held", default_value, check_held,
                                   UsdGeom.Tokens.vertex)

    def GetBiaxialAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.BIAXIAL)

    def CreateBiaxialAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create(schema.BIAXIAL, Sdf.ValueTypeNames.Float,
                            None if default_value is None else float(default_value),
                            lambda v: check_biaxial(v, self._path()))

    def GetTensionAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.TENSION)

    def CreateTensionAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create(schema.TENSION, Sdf.ValueTypeNames.Float,
                            None if default_value is None else float(default_value),
                            lambda v: check_tension(v, self._path()))

    def GetTensionThresholdAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.TENSION_THRESHOLD)

    def CreateTensionThresholdAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create(schema.TENSION_THRESHOLD, Sdf.ValueTypeNames.Float,
                            None if default_value is None else float(default_value),
                            lambda v: check_tension_threshold(v, self._path()))

    def GetHeightProfileAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.HEIGHT_PROFILE)

    def CreateHeightProfileAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create_profile(schema.HEIGHT_PROFILE, default_value)

    def GetGradientProfileAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.GRADIENT_PROFILE)

    def CreateGradientProfileAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        return self._create_profile(schema.GRADIENT_PROFILE, default_value)

    def _create_profile(self, name: str, default_value) -> Usd.Attribute:
        value = None if default_value is None else Vt.FloatArray.FromNumpy(
            np.asarray(default_value, np.float32))
        return self._create(name, Sdf.ValueTypeNames.FloatArray, value,
                            lambda v: check_profile(v, name, self._path()))

    def GetRelaxIterationsAttr(self) -> Usd.Attribute:  # noqa: N802
        return self._attr(schema.RELAX_ITERATIONS)

    def CreateRelaxIterationsAttr(self, default_value=None) -> Usd.Attribute:  # noqa: N802
        # the reader's own check (usd/validation.py), so that what is authored is what renders
        return self._create(schema.RELAX_ITERATIONS, Sdf.ValueTypeNames.Int,
                            None if default_value is None else int(default_value),
                            lambda v: check_relax_iterations(v, self._path()))

    # -- numpy conveniences -----------------------------------------------------------
    def get_q(self, time=Usd.TimeCode.Default()) -> np.ndarray:  # noqa: B008
        """(n, 3) float32; zeros when q is not authored."""
        primvar = self.GetQPrimvar()
        value = flattened(primvar, time) if primvar and primvar.HasAuthoredValue() \
            else None
        if value is None:
            return np.zeros((self._point_count() or 0, 3), np.float32)
        return np.asarray(value, np.float32).reshape(-1, 3)

    def set_q(self, q, time=Usd.TimeCode.Default()) -> None:  # noqa: B008
        """Set q from an (n, 3) array; checks length, finiteness and |q| <= 1 first."""
        arr = np.asarray(q, dtype=np.float32).reshape(-1, 3)
        refuse(check_q(arr, UsdGeom.Tokens.vertex, self._point_count(), self._path()))
        primvar = self._primvars().CreatePrimvar("wrinkle:q", Sdf.ValueTypeNames.Vector3fArray,
                                                 UsdGeom.Tokens.vertex)
        primvar.SetInterpolation(UsdGeom.Tokens.vertex)
        primvar.Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(arr)), time)

    def clear_q(self) -> None:
        """Remove the painted q (the mesh keeps its WrinkleAPI)."""
        self._primvars().RemovePrimvar("wrinkle:q")

    def set_profile(self, height, gradient=None) -> None:
        """Author a height profile; the gradient is derived unless given."""
        height = np.asarray(height, np.float32)
        gradient = derive_gradient(height) if gradient is None else np.asarray(gradient,
                                                                               np.float32)
        self.CreateHeightProfileAttr(height)
        self.CreateGradientProfileAttr(gradient)
