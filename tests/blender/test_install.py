"""The add-on as a user installs it: Blender's add-on installer takes the zip the build makes
(Edit > Preferences > Add-ons > Install...), and enabling it puts bounce in the render engine
list, with a property for every row of the parameter table Blender does not own."""

import os
import sys

import addon_utils
import bpy
import pytest

import bounce

ZIP = os.environ.get("BOUNCE_ADDON_ZIP", "")


@pytest.mark.skipif(not os.path.isfile(ZIP) or not os.environ.get("BLENDER_USER_SCRIPTS"),
                    reason="needs the build's zip and a scripts folder of its own (CTest's Blender.Addon sets both)")
def test_the_installer_takes_the_zip_and_bounce_is_an_engine(monkeypatch):
    # The installed copy, not the checkout's folder the other tests import.
    for name in [m for m in sys.modules if m == "bounce_render" or m.startswith("bounce_render.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if not p.endswith(os.sep + "blender")])
    bpy.ops.preferences.addon_install(filepath=ZIP, overwrite=True)
    module = addon_utils.enable("bounce_render", default_set=True)
    try:
        assert module is not None and module.__file__.startswith(os.environ["BLENDER_USER_SCRIPTS"])
        assert "BOUNCE" in {e.bl_idname for e in bpy.types.RenderEngine.__subclasses__()}
        bpy.context.scene.render.engine = "BOUNCE"
        assert bpy.context.scene.render.engine == "BOUNCE"
        # Every render.* row has its property (an "auto" row two), none written by hand.
        rows = [r for r in bounce.params() if r["key"].startswith("render.") and r["key"] not in module.settings.OWNED_BY_BLENDER]
        props = bpy.context.scene.bounce.bl_rna.properties
        for row in rows:
            assert row["key"].split(".", 1)[1] in props, row["key"]
        render_rows = [r for r in bounce.params() if r["key"].startswith("render.")]
        assert len(rows) == len(render_rows) - 2 > 60 and bpy.context.scene.bounce.gi == "cache"
    finally:
        addon_utils.disable("bounce_render")
