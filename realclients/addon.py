"""Install and enable usdwrinkle's Blender add-on in a client, as a user does (Edit >
Preferences > Add-ons > Install from Disk, then the checkbox): Blender's own
``preferences.addon_install`` and ``addon_utils.enable``. The client runs with
BLENDER_USER_SCRIPTS in its scratch folder (realclients/__init__.py), so nothing lands in
the user's Blender configuration."""
from __future__ import annotations

MODULE = "usdwrinkle_blender"


class Installed:
    """The enabled add-on; disable() turns it off again (the next job imports without)."""

    def __init__(self, module):
        self.module = module

    def unregister(self) -> None:
        import addon_utils

        addon_utils.disable(MODULE, default_set=True)


def register(path: str) -> Installed:
    """Install the add-on file at ``path`` and enable it; raises when Blender refuses."""
    import addon_utils
    import bpy

    if bpy.ops.preferences.addon_install(filepath=path, overwrite=True) != {"FINISHED"}:
        raise RuntimeError(f"Blender did not install the add-on {path}")
    module = addon_utils.enable(MODULE, default_set=True)
    if module is None:
        raise RuntimeError(f"Blender could not enable the add-on {MODULE}")
    return Installed(module)
