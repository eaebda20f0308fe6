"""bounce as a Blender render engine: F12 exports the evaluated scene (export.py), renders it
through the Python module with progress and Esc, and writes bounce's layers into the render
result as passes for the compositor. Render Animation renders the frame range as one shot,
records kept across frames (shot.py)."""

import os

import bpy
import numpy as np

import bounce

from . import export, settings, shot, viewport

# bounce's layers under Blender's own pass names where Blender has one (the compositor's
# Defocus and Vector nodes find them); the others keep bounce's names.
PASS_NAMES = {"depth": ("Depth", "Z"), "N": ("Normal", "XYZ")}


VIEWPORT_SCALE = 0.5  # the rendered viewport's pixels per region pixel


class EscPressed(Exception):
    """Raised from the progress callback when Blender asks the render to stop."""


def pass_of(layer, channels):
    """(Blender pass name, channel ids) of a bounce layer."""
    if layer in PASS_NAMES:
        return PASS_NAMES[layer]
    ids = "".join(c.rsplit(".", 1)[-1][0] for c in channels)
    return layer, ids if len(ids) == len(channels) else "XYZW"[: len(channels)]


def esc_pressed(engine):
    """Whether Blender asks the render to stop (Esc, or the render window closed)."""
    return engine.test_break()


def callbacks_of(engine_now):
    """render()'s progress and preview callbacks, reporting to the engine engine_now() names."""

    def progress(phase, done, total, elapsed):
        engine = engine_now()
        if esc_pressed(engine):
            raise EscPressed()
        engine.update_progress(done / total if total else 0.0)
        engine.update_stats("", f"bounce: {phase} {done}/{total}, {elapsed:.1f} s")

    def preview(image):
        engine = engine_now()
        if esc_pressed(engine):
            raise EscPressed()
        result = engine.begin_result(0, 0, image.width, image.height)
        result.layers[0].passes["Combined"].rect = np.flipud(image["beauty"]).reshape(-1, 4)
        engine.end_result(result)

    return {"progress": progress, "preview": preview}


class BounceRenderEngine(bpy.types.RenderEngine):
    bl_idname = "BOUNCE"
    bl_label = "bounce"
    bl_use_preview = False
    bl_use_postprocess = True

    def render(self, depsgraph):
        try:
            image = shot.render_frame(self, depsgraph) if self.is_animation else self.render_still(depsgraph)
        except EscPressed:
            self.report({"INFO"}, "bounce: cancelled")
            return
        except (bounce.Error, ValueError, OSError) as e:  # one line in Blender's report, never a traceback
            self.report({"ERROR"}, f"bounce: {e}")
            return
        if image is not None:
            self.write_result(image)

    def render_still(self, depsgraph):
        path, report = export.export_scene(depsgraph, export.export_folder(depsgraph.scene),
                                           settings.changed_settings(depsgraph.scene.bounce, depsgraph.scene))
        report.send(self)
        return bounce.Scene.load(path).render(**self.callbacks())

    def callbacks(self):
        """The progress, preview and cancel of a still, as Blender shows and asks them."""
        return callbacks_of(lambda: self)

    def shot_callbacks(self):
        """The same for a shot, whose frames Blender may hand to a new engine each."""
        return callbacks_of(shot.current_engine)

    def write_result(self, image):
        """Every layer of `image` into the render result: beauty as Combined, the rest as passes."""
        for layer in image.layers:
            if layer != "beauty":
                name, ids = pass_of(layer, image.channels(layer))
                if layer not in PASS_NAMES:  # Blender's own passes are there already
                    self.add_pass(name, len(ids), ids)
        result = self.begin_result(0, 0, image.width, image.height)
        passes = result.layers[0].passes
        for layer in image.layers:
            name = "Combined" if layer == "beauty" else pass_of(layer, image.channels(layer))[0]
            target = passes.find_by_name(name, "")
            if target is None:
                continue
            pixels = np.flipud(image[layer]).reshape(image.width * image.height, -1)  # Blender's rows go up
            target.rect = pixels[:, : target.channels] if pixels.shape[1] >= target.channels else np.pad(pixels, ((0, 0), (0, target.channels - pixels.shape[1])))
        self.end_result(result)

    # The rendered viewport (viewport.py): a session kept while only lights and the view change.

    def viewport_camera(self, context, depsgraph):
        """The viewport's view at VIEWPORT_SCALE of its pixels (the scene camera in camera view)."""
        region, view = context.region, context.region_data
        w, h = max(16, round(region.width * VIEWPORT_SCALE)), max(16, round(region.height * VIEWPORT_SCALE))
        if view.view_perspective == "CAMERA":
            camera = export.camera_entry(depsgraph.scene, depsgraph, viewport.Report())
            camera["resolution"] = [w, h]  # the camera's view, drawn over the whole region
            return camera
        return viewport.view_camera(view, context.space_data.lens, w, h)

    def view_sync(self, context, depsgraph, only_lights):
        scene = depsgraph.scene
        if getattr(self, "_viewport", None) is None:
            self._viewport = viewport.Viewport(os.path.join(export.export_folder(scene), "viewport"))
        try:
            action = self._viewport.sync(depsgraph, settings.changed_settings(scene.bounce, scene), self.viewport_camera(context, depsgraph),
                                         only_lights)
        except (bounce.Error, ValueError, OSError) as e:
            self.report({"ERROR"}, f"bounce: {e}")
            return
        if action is not None:
            self.update_stats("", f"bounce: {action}")

    def view_update(self, context, depsgraph):
        lights_only = all(isinstance(u.id, bpy.types.Light) or (isinstance(u.id, bpy.types.Object) and u.id.type == "LIGHT")
                          for u in depsgraph.updates)
        self.view_sync(context, depsgraph, lights_only)

    def view_draw(self, context, depsgraph):
        # Navigating the view calls only this: a new view is a new deep buffer (rasterize).
        vp = getattr(self, "_viewport", None)
        if vp is None or vp.doc is None or vp.doc["camera"] != self.viewport_camera(context, depsgraph):
            self.view_sync(context, depsgraph, True)
            vp = getattr(self, "_viewport", None)
        if vp is not None:
            vp.draw(self, context)

    def update_render_passes(self, scene=None, renderlayer=None):
        """The passes the compositor offers: bounce's layers as the settings will make them."""
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        s = scene.bounce
        names = ["direct", "albedo"] + (["indirect"] if s.gi != "none" else []) + (["ao"] if s.ao else [])
        for name in names:
            self.register_pass(scene, renderlayer, name, 1 if name == "ao" else 3, "Y" if name == "ao" else "RGB",
                               "VALUE" if name == "ao" else "COLOR")
        self.register_pass(scene, renderlayer, "Depth", 1, "Z", "VALUE")
        self.register_pass(scene, renderlayer, "Normal", 3, "XYZ", "VECTOR")
