"""The evaluated depsgraph as a bounce scene file (docs/blender.md): the camera, lights and
world, every mesh with its modifiers applied written once as PLY files per material slot,
Blender's instances (collection, particle and geometry-node instances) as placements of one
prototype, per-object visibility and holdouts. Blender's Z-up world is turned to bounce's
Y-up (x, y, z) -> (x, z, -y), as glTF does."""

import json
import math
import os
import tempfile

import bpy
from mathutils import Matrix

from . import lights, materials, meshes
from .report import Report

TO_BOUNCE = Matrix(((1, 0, 0, 0), (0, 0, 1, 0), (0, -1, 0, 0), (0, 0, 0, 1)))
GEOMETRY = {"MESH", "CURVE", "SURFACE", "FONT", "META"}


def export_folder(scene):
    """Where a render's scene file, meshes and images go: the settings' folder, else a
    temporary one per Blender session and scene."""
    if scene.bounce_export_dir:
        return bpy.path.abspath(scene.bounce_export_dir)
    return os.path.join(bpy.app.tempdir or tempfile.gettempdir(), "bounce", bpy.path.clean_name(scene.name))


def _name(text):
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in text)


def _matrix(m):
    return [round(float(m[r][c]), 9) for r in range(4) for c in range(4)]


def camera_entry(scene, depsgraph, report):
    cam_obj = scene.camera
    if cam_obj is None:
        raise ValueError("the scene has no camera")
    cam_obj = cam_obj.evaluated_get(depsgraph)
    cam = cam_obj.data
    r = scene.render
    w = max(1, round(r.resolution_x * r.resolution_percentage / 100))
    h = max(1, round(r.resolution_y * r.resolution_percentage / 100))
    if cam.type != "PERSP":
        report.add(f"camera {cam_obj.name}: a {cam.type.lower()} camera rendered as a perspective one")
    if cam.shift_x or cam.shift_y:
        report.add(f"camera {cam_obj.name}: lens shift is not read")
    if r.pixel_aspect_x != r.pixel_aspect_y:
        report.add("non-square pixels are rendered square")
    fit = cam.sensor_fit
    if fit == "AUTO":
        fit = "HORIZONTAL" if w >= h else "VERTICAL"
        sensor = cam.sensor_width
    else:
        sensor = cam.sensor_width if fit == "HORIZONTAL" else cam.sensor_height
    half = math.atan(sensor / (2 * cam.lens))
    vfov = 2 * math.atan(math.tan(half) * h / w) if fit == "HORIZONTAL" else 2 * half
    m = TO_BOUNCE @ cam_obj.matrix_world
    pos, forward, up = m.translation, -(m.col[2].xyz.normalized()), m.col[1].xyz.normalized()
    entry = {"position": list(pos), "look_at": list(pos + forward), "up": list(up), "fov": math.degrees(vfov),
             "resolution": [w, h]}
    if cam.dof.use_dof:
        focus = cam.dof.focus_distance
        if cam.dof.focus_object is not None:
            target = (TO_BOUNCE @ cam.dof.focus_object.matrix_world).translation
            focus = max(1e-4, (target - pos).dot(forward))
        entry["aperture"] = cam.lens / 1000 / cam.dof.aperture_fstop  # mm -> scene units (metres)
        entry["focus_distance"] = focus
    return entry


def visibility(obj):
    """The object's visible_to and matte keys (only what differs from bounce's defaults)."""
    out = {}
    flags = {"camera": obj.visible_camera, "shadows": obj.visible_shadow, "indirect": obj.visible_diffuse,
             "reflections": obj.visible_glossy or obj.visible_transmission}
    if not all(flags.values()):
        out["visible_to"] = flags
    if obj.is_holdout:
        out["matte"] = True
    return out


class SceneExport:
    def __init__(self, depsgraph, folder, report=None):
        self.depsgraph = depsgraph
        self.scene = depsgraph.scene
        self.folder = folder
        self.report = report or Report()
        self.materials = materials.MaterialExport(folder, self.report)
        self.files = {}        # geometry key -> {slot: (ply file, bounce material)}
        self.objects = []
        self.placements = {}   # prototype key -> [(name, matrix, object)]
        self.lights = []
        self.entries = {}      # Blender object (not an instance) -> its scene-file objects
        self.light_names = {}  # Blender light object -> its scene-file light

    def geometry(self, key, obj):
        """The PLY files of `obj`'s evaluated geometry, written once per key."""
        if key not in self.files:
            try:
                mesh = obj.to_mesh()
            except RuntimeError:
                mesh = None
            files = {}
            if mesh is not None:
                for slot, (p, n, uv) in meshes.mesh_arrays(mesh).items():
                    path = os.path.join(self.folder, f"mesh{len(self.files)}_{slot}.ply")
                    meshes.write_ply(path, p, n, uv)
                    mat = obj.material_slots[slot].material if slot < len(obj.material_slots) else None
                    files[slot] = (os.path.basename(path), self.materials.name_of(mat))
                obj.to_mesh_clear()
            self.files[key] = files
        return self.files[key]

    def add_light(self, inst):
        """A light of the depsgraph (an instanced one named apart by its place in the list)."""
        obj = inst.object
        name = _name(obj.name if not inst.is_instance else f"{obj.name}_{len(self.lights)}")
        entry = lights.light_entry(name, obj.data, TO_BOUNCE @ inst.matrix_world, self.report)
        if entry is not None:
            self.lights.append(entry)
            if not inst.is_instance:
                self.light_names[obj.name_full] = entry

    def light_list(self):
        """The scene file's lights alone (no mesh written): the depsgraph's lights and the sky."""
        for inst in self.depsgraph.object_instances:
            if inst.object.type == "LIGHT":
                self.add_light(inst)
        sky = lights.world_light(self.scene.world, self.materials, self.report)
        return self.lights + ([sky] if sky is not None else [])

    def add_instance(self, inst):
        """A geometry instance of the depsgraph (lights are light_list's)."""
        obj = inst.object
        m = TO_BOUNCE @ inst.matrix_world
        if obj.type not in GEOMETRY:
            if obj.type not in ("CAMERA", "EMPTY", "ARMATURE", "LIGHT_PROBE"):
                self.report.add(f"object {obj.name}: a {obj.type.lower()} is not exported")
            return
        if inst.is_instance:
            key = ("instance", obj.original.name_full if obj.original else obj.name_full, obj.data.name_full if obj.data else "")
            self.placements.setdefault(key, []).append((m.copy(), obj))
            self.geometry(key, obj)
            return
        files = self.geometry(("object", obj.name_full), obj)
        for slot, (ply, mat) in files.items():
            entry = {"name": _name(obj.name) + (f"/{slot}" if len(files) > 1 else ""), "type": "mesh", "file": ply,
                     "material": mat, "transform": {"matrix": _matrix(m)}}
            entry.update(visibility(obj))
            self.objects.append(entry)
            self.entries.setdefault(obj.name_full, []).append(entry)

    def add_placements(self):
        for key, placed in self.placements.items():
            for slot, (ply, mat) in self.files[key].items():
                proto = _name(key[1]) + f"/proto{slot}"
                if mat in self.materials.emissive:
                    # A prototype cannot emit (docs/instancing.md): each placement is an object.
                    for k, (m, o) in enumerate(placed):
                        self.objects.append({"name": f"{proto}/{k}", "type": "mesh", "file": ply, "material": mat,
                                             "transform": {"matrix": _matrix(m)}, **visibility(o)})
                    continue
                self.objects.append({"name": proto, "type": "mesh", "file": ply, "material": mat, "prototype": True})
                self.objects.append({"name": _name(key[1]) + f"/instances{slot}", "instances": {"of": proto, "transforms": [
                    {"matrix": _matrix(m), **visibility(o)} for m, o in placed]}})

    def run(self, render_settings):
        for inst in self.depsgraph.object_instances:
            if inst.object.type != "LIGHT":
                self.add_instance(inst)
        self.lights = self.light_list()
        self.add_placements()
        if not self.objects:
            raise ValueError("nothing to render: the scene has no mesh")
        doc = {"description": f"Exported from Blender {bpy.app.version_string} by the bounce add-on: scene {self.scene.name}, frame {self.scene.frame_current}",
               "camera": camera_entry(self.scene, self.depsgraph, self.report),
               "render": render_settings, "materials": self.materials.materials, "objects": self.objects}
        if self.lights:
            doc["lights"] = self.lights
        return doc


def write_scene(folder, doc):
    path = os.path.join(folder, "scene.json")
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
    return path


def export_scene(depsgraph, folder, render_settings, report=None):
    """Writes folder/scene.json (and its meshes and images); returns its path and the report."""
    os.makedirs(folder, exist_ok=True)
    export = SceneExport(depsgraph, folder, report)
    return write_scene(folder, export.run(render_settings)), export.report
