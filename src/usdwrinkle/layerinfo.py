"""The stage metadata a layer over a stage must carry itself (pxr only: usdview's plugin
imports it in a Python without numpy)."""
from __future__ import annotations

#: read by a stage from its root layer only, never from a sublayer: a layer that sublayers
#: a stage and becomes a root itself (a paint layer, usdview's held stage) copies them
STAGE_INFO_KEYS = ("startTimeCode", "endTimeCode", "timeCodesPerSecond", "framesPerSecond",
                   "metersPerUnit", "upAxis")


def copy_stage_info(source, layer) -> None:
    """Copy the STAGE_INFO_KEYS that the Sdf.Layer ``source`` authors onto ``layer``."""
    for key in STAGE_INFO_KEYS:
        if source.pseudoRoot.HasInfo(key):
            layer.pseudoRoot.SetInfo(key, source.pseudoRoot.GetInfo(key))
