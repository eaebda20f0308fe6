"""Render Animation as one bounce shot (docs/blender.md): on the animation's first frame the
range is exported once as a keyed scene file (objects' placements as translate, rotate and
scale keys, the camera's pose and lens, the lights' values, one key per frame, linear between)
and a bounce.Frames iterator renders one frame per call of the engine, each starting from the
records the one before left, as `bounce render --frames` does. What changes over the range and
cannot be keyed (a deforming mesh, moving instances) is taken at the first frame and reported."""

import math
import os

import numpy as np

import bounce

from . import camera_keys, export, settings
from .report import Report

_shots = {}  # scene name -> the shot being rendered


def _trs(m):
    loc, rot, scale = m.decompose()
    axis, angle = rot.to_axis_angle()
    return [list(loc), [math.degrees(angle), *axis], list(scale)]


def _shape(obj):
    """A fingerprint of the evaluated mesh's vertices (a deforming mesh changes it)."""
    if obj.type != "MESH":
        return 0
    co = np.empty(len(obj.data.vertices) * 3, np.float32)
    obj.data.vertices.foreach_get("co", co)
    return hash(co.tobytes())


def _keys(samples):
    """{"keys": [[frame, value]...], "interpolation": "linear"} of per-frame samples."""
    return {"keys": [[f, v] for f, v in samples], "interpolation": "linear"}


class ShotExport:
    """The scene at the first frame, plus what changes over the range, sampled per frame."""

    def __init__(self, engine, depsgraph, first, last, folder):
        self.engine, self.depsgraph, self.folder = engine, depsgraph, folder
        self.first, self.last = first, last
        self.report = Report()

    def pose(self):
        """This frame's placements (bounce space), geometry fingerprints, lights and camera."""
        lights = export.SceneExport(self.depsgraph, self.folder, Report())
        lights.light_list()
        out = {"objects": {}, "shapes": {}, "instances": [], "lights": lights.light_names}
        for inst in self.depsgraph.object_instances:
            obj = inst.object
            m = export.TO_BOUNCE @ inst.matrix_world
            if inst.is_instance:
                out["instances"].append([round(x, 6) for x in export._matrix(m)])
            elif obj.type in export.GEOMETRY:
                out["objects"][obj.name_full] = m.copy()
                out["shapes"][obj.name_full] = _shape(obj)
        out["camera"] = export.camera_entry(self.depsgraph.scene, self.depsgraph, Report())
        return out

    def run(self, render_settings):
        scene = self.depsgraph.scene
        poses = {}
        for f in range(self.first, self.last + 1):
            self.engine.frame_set(f, 0.0)
            poses[f] = self.pose()
        self.engine.frame_set(self.first, 0.0)
        export_ = export.SceneExport(self.depsgraph, self.folder, self.report)
        doc = export_.run(render_settings)
        first = poses[self.first]
        frames = sorted(poses)
        for name, entries in export_.entries.items():
            mats = [poses[f]["objects"].get(name) for f in frames]
            if any(m is None for m in mats):
                self.report.add(f"object {name} is not there on every frame: taken at the first frame")
                continue
            if any(poses[f]["shapes"][name] != first["shapes"][name] for f in frames):
                self.report.add(f"object {name} changes shape over the shot: its first frame's shape is rendered")
            if all(m == mats[0] for m in mats):
                continue
            trs = [_trs(m) for m in mats]
            for entry in entries:
                entry["transform"] = {key: _keys([(f, t[i]) for f, t in zip(frames, trs)])
                                      for i, key in enumerate(("translate", "rotate", "scale"))}
        if any(poses[f]["instances"] != first["instances"] for f in frames):
            self.report.add("instances move over the shot: their first frame's placements are rendered")
        for name, entry in export_.light_names.items():
            for key in ("position", "direction", "intensity", "color", "corner", "edge_u", "edge_v", "cone_angle", "cone_falloff"):
                values = [poses[f]["lights"].get(name, {}).get(key) for f in frames]
                if key in entry and any(v != values[0] for v in values) and all(v is not None for v in values):
                    entry[key] = _keys(list(zip(frames, values)))
        camera_keys.add(doc["camera"], [(f, poses[f]["camera"]) for f in frames])
        doc["animation"] = {"fps": scene.render.fps / scene.render.fps_base, "frames": [self.first, self.last]}
        return export.write_scene(self.folder, doc)


class Shot:
    def __init__(self, path, first, last, callbacks):
        self.next = first
        self.last = last
        self.frames = bounce.Scene.load(path).render_frames(range(first, last + 1), **callbacks)


def render_frame(engine, depsgraph):
    """This frame of the running shot; the shot starts (is exported) on its first frame."""
    scene = depsgraph.scene
    f = scene.frame_current
    shot = _shots.get(scene.name)
    if shot is None or shot.next != f:
        if scene.frame_step != 1:
            engine.report({"WARNING"}, "bounce: a frame step other than 1 renders each frame alone (records are not kept)")
            return engine.render_still(depsgraph)
        folder = os.path.join(export.export_folder(scene), "shot")
        os.makedirs(folder, exist_ok=True)
        exporter = ShotExport(engine, depsgraph, f, scene.frame_end, folder)
        path = exporter.run(settings.changed_settings(scene.bounce, scene))
        exporter.report.send(engine)
        shot = _shots[scene.name] = Shot(path, f, scene.frame_end, engine.shot_callbacks())
    _current[0] = engine
    try:
        image = next(shot.frames)
    except BaseException:
        _shots.pop(scene.name, None)
        raise
    shot.next = f + 1
    if f >= shot.last:
        _shots.pop(scene.name, None)
    return image


_current = [None]  # the engine rendering the shot's current frame (Blender may make one per frame)


def current_engine():
    return _current[0]
