"""bounce's settings on Blender's Render Properties, generated from the parameter table
(bounce.params()): one property per `render.*` row, one panel per stage, each with the row's
doc, range and default. No list of parameters is written here; Blender owns the rows it has
its own control for (the camera, the resolution, the threads, the border)."""

import bpy

import bounce

OWNED_BY_BLENDER = {"render.crop", "render.threads"}
# Where the add-on's default differs from the CLI's: F12 gathers through the cache and shows
# the image as it refines.
ADDON_DEFAULTS = {"render.gi": "cache", "render.preview": True}
INT_MAX = 2**31 - 1


def rows():
    """The table's rows the panel shows, in table order."""
    return [r for r in bounce.params() if r["key"].startswith("render.") and r["key"] not in OWNED_BY_BLENDER]


def _name(row):
    return row["key"].split(".", 1)[1]


def _default(row):
    return ADDON_DEFAULTS.get(row["key"], row["default"])


def _property(row):
    """(annotations) the Blender properties of one row: its value, and for "auto" rows a switch."""
    name, kind, default, doc = _name(row), row["type"], _default(row), row["doc"][:1000]
    lo, hi = row.get("range", [None, None])
    label = name.replace("_", " ").capitalize()
    if kind == "boolean":
        return {name: bpy.props.BoolProperty(name=label, description=doc, default=default)}
    if kind == "enum":
        items = [(c, c, "") for c in row["choices"]]
        return {name: bpy.props.EnumProperty(name=label, description=doc, items=items, default=default)}
    if kind == "path":
        return {name: bpy.props.StringProperty(name=label, description=doc, default=default, subtype="DIR_PATH")}
    if kind in ("integer", "unsigned integer"):
        return {name: bpy.props.IntProperty(name=label, description=doc, default=int(default), min=int(max(lo, -INT_MAX)),
                                            max=int(min(hi, INT_MAX)))}
    if kind == "number":
        return {name: bpy.props.FloatProperty(name=label, description=doc, default=float(default), min=lo, max=hi, precision=4)}
    if kind == 'number or "auto"':
        auto = default == "auto"
        return {name: bpy.props.FloatProperty(name=label, description=doc, default=0.0 if auto else float(default), min=lo,
                                              max=hi, precision=4),
                name + "_auto": bpy.props.BoolProperty(name="Auto", description=f"{label}: automatic ({doc})", default=auto)}
    return {}


def changed_settings(settings, scene):
    """The scene file's "render" object: the rows whose value differs from the table's default."""
    out = {}
    for row in rows():
        name, default = _name(row), row["default"]
        if not hasattr(settings, name):
            continue
        value = getattr(settings, name)
        if row["type"] == 'number or "auto"':
            value = "auto" if getattr(settings, name + "_auto") else float(value)
        if isinstance(value, float) and isinstance(default, (int, float)):
            same = abs(value - default) <= 1e-6 * max(1.0, abs(default))
        else:
            same = value == default
        if not same:
            out[name] = value
    if scene.render.threads_mode == "FIXED":
        out["threads"] = scene.render.threads
    return out


def stages():
    seen = []
    for row in rows():
        if row["stage"] not in seen:
            seen.append(row["stage"])
    return seen


class BouncePanel:
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {"BOUNCE"}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        settings = context.scene.bounce
        layout = self.layout
        layout.use_property_split = True
        for row in rows():
            if row["stage"] != self.stage:
                continue
            name = _name(row)
            if row["type"] == 'number or "auto"':
                line = layout.row(heading=name.replace("_", " ").capitalize())
                line.prop(settings, name + "_auto")
                sub = line.row()
                sub.active = not getattr(settings, name + "_auto")
                sub.prop(settings, name, text="")
            else:
                layout.prop(settings, name)


def make_classes():
    annotations = {}
    for row in rows():
        annotations.update(_property(row))
    settings = type("BounceSettings", (bpy.types.PropertyGroup,), {"__annotations__": annotations})
    panels = []
    for i, stage in enumerate(stages()):
        panels.append(type(f"RENDER_PT_bounce_{stage}", (BouncePanel, bpy.types.Panel), {
            "bl_label": f"bounce: {stage}", "stage": stage,
            "bl_options": set() if stage in ("gather", "cache") else {"DEFAULT_CLOSED"}}))
    return [settings, *panels]
