"""bounce as a Blender render engine (docs/blender.md).

Install: Edit > Preferences > Add-ons > Install... and pick this folder zipped (or link the
folder into ~/.config/blender/3.4/scripts/addons/); the bounce Python module must be
importable by Blender's Python (`make render` makes it so for Debian's Blender)."""

bl_info = {
    "name": "bounce",
    "author": "the bounce developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Render Properties > Render Engine > bounce",
    "description": "One bounce of diffuse interreflection and ambient occlusion through an irradiance cache",
    "doc_url": "https://github.com/bounce-renderer/bounce/blob/main/docs/blender.md",
    "category": "Render",
}

_classes = []


def register():
    import bpy

    try:
        import bounce  # noqa: F401 (the module the add-on is built on)
    except ImportError as e:
        raise ImportError(f"the bounce add-on needs the bounce Python module (make render builds it; docs/python.md): {e}") from e
    from . import engine, settings

    _classes[:] = settings.make_classes() + [engine.BounceRenderEngine]
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.bounce = bpy.props.PointerProperty(type=_classes[0])
    bpy.types.Scene.bounce_export_dir = bpy.props.StringProperty(
        name="Export folder", subtype="DIR_PATH", default="",
        description="Where a render writes its scene file, meshes and images (empty: a temporary folder)")
    # Blender's own panels that apply to any engine (dimensions, output, colour management).
    for panel in ("RENDER_PT_format", "RENDER_PT_frame_range", "RENDER_PT_output", "RENDER_PT_color_management"):
        cls = getattr(bpy.types, panel, None)
        if cls is not None and hasattr(cls, "COMPAT_ENGINES"):
            cls.COMPAT_ENGINES.add("BOUNCE")


def unregister():
    import bpy

    del bpy.types.Scene.bounce
    del bpy.types.Scene.bounce_export_dir
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
    _classes.clear()
