"""The rendered viewport (docs/blender.md): a bounce.Session (the lighting tool's engine) on the
scene as exported, kept while only lights and the view change, so a light's edit re-shades
from the deep buffer and cache the last render left instead of rendering anew. Blender calls
view_update after an edit and view_draw to draw: sync() is the first, draw() the second."""

import json
import math
import os
import shutil

import numpy as np

import bounce

from . import export
from .report import Report

# Light values the lighting tool edits in place (a re-shade); anything else makes a new session.
LIGHT_KEYS = ("position", "direction", "intensity", "color", "corner", "edge_u", "edge_v", "cone_angle", "cone_falloff")


def view_camera(region_data, lens, width, height):
    """The viewport's own view as the scene file's camera (sensor 36 mm across the longer side)."""
    m = export.TO_BOUNCE @ region_data.view_matrix.inverted()
    pos, forward, up = m.translation, -(m.col[2].xyz.normalized()), m.col[1].xyz.normalized()
    half = math.atan(36 / (2 * lens))
    vfov = 2 * math.atan(math.tan(half) * height / width) if width >= height else 2 * half
    return {"position": list(pos), "look_at": list(pos + forward), "up": list(up), "fov": math.degrees(vfov), "resolution": [width, height]}


class Viewport:
    """One viewport's session: the exported scene, and what changes between syncs."""

    def __init__(self, folder):
        self.folder = folder
        self.session = None
        self.doc = None
        self.image = None
        self.last_action = None
        self.sessions = 0

    def sync(self, depsgraph, render_settings, camera=None, only_lights=False):
        """Brings the session up to `depsgraph` and renders what changed; returns the action
        ("rasterize" for a new session or view, "reshade", ...) or None when nothing did."""
        report = Report()
        if only_lights and self.doc is not None:
            doc = dict(self.doc, lights=export.SceneExport(depsgraph, self.folder, report).light_list())
        else:
            doc = export.SceneExport(depsgraph, self.folder, report).run(render_settings)
        if camera is not None:
            doc["camera"] = camera
        if self.doc is not None and doc == self.doc:
            return None
        if self.session is None or not self._edit(doc):
            path = export.write_scene(self.folder, doc)
            # A session resumes from the files in its folder (as `bounce light` restarted does):
            # a new scene starts in a folder of its own, the last one's removed.
            self.sessions += 1
            out = os.path.join(self.folder, f"session{self.sessions}")
            shutil.rmtree(os.path.join(self.folder, f"session{self.sessions - 1}"), ignore_errors=True)
            shutil.rmtree(out, ignore_errors=True)
            self.session = bounce.Session(scene=path, out_dir=out)
        self.doc = json.loads(json.dumps(doc))  # a copy: later exports compare against it
        action = self.session.pending or "reshade"
        self.image = self.session.render()
        self.last_action = action
        return action

    def _edit(self, doc):
        """The changes from the last doc as the session's edits; False when they are not edits
        the session takes (objects, materials, the number or kind of lights)."""
        before, now = self.doc, json.loads(json.dumps(doc))
        if {k: v for k, v in before.items() if k not in ("lights", "camera", "description")} != \
                {k: v for k, v in now.items() if k not in ("lights", "camera", "description")}:
            return False
        old, new = before.get("lights", []), now.get("lights", [])
        if [(l["type"], l["name"]) for l in old] != [(l["type"], l["name"]) for l in new]:
            return False
        for i, (a, b) in enumerate(zip(old, new)):
            if set(a) != set(b) or any(a[k] != b[k] for k in a if k not in LIGHT_KEYS):
                return False
            for key in LIGHT_KEYS:
                if key in b and a[key] != b[key]:
                    self.session[f"lights.{i}.{key}"] = b[key]
        for key, value in now["camera"].items():
            if before["camera"].get(key) != value:
                self.session[f"camera.{key}"] = value
        return True

    def draw(self, engine, context):
        """Draws the last image over the region (Blender's display transform applied)."""
        if self.image is None:
            return
        import gpu
        from gpu_extras.presets import draw_texture_2d

        rgba = np.ascontiguousarray(np.flipud(self.image["beauty"]), dtype=np.float32)
        h, w = rgba.shape[:2]
        texture = gpu.types.GPUTexture((w, h), format="RGBA16F", data=gpu.types.Buffer("FLOAT", w * h * 4, rgba.ravel()))
        gpu.state.blend_set("ALPHA_PREMULT")
        engine.bind_display_space_shader(context.scene)
        draw_texture_2d(texture, (0, 0), context.region.width, context.region.height)
        engine.unbind_display_space_shader()
        gpu.state.blend_set("NONE")
