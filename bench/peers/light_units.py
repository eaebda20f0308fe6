"""Blender's light units against bounce's, as the add-on converts them (issue 64, item 5): a white
floor (albedo 0.8) under one light of each type (point, spot, sun, area), rendered by Cycles
(its diffuse direct pass times diffuse colour) and by bounce through the add-on (its direct
layer), the same camera; prints the ratio of their means over the image. Run inside Debian's
Blender:
    blender -b --factory-startup -P bench/peers/light_units.py -- [out folder]"""
import math
import os
import sys

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path[:0] = [os.path.join(ROOT, "blender"), os.path.join(ROOT, "build", "python")]
import bounce  # noqa: E402
import bounce_render  # noqa: E402

OUT = sys.argv[sys.argv.index("--") + 1] if "--" in sys.argv else "/tmp/light-units"


def scene_with(kind):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x = scene.render.resolution_y = 64
    scene.render.resolution_percentage = 100
    m = bpy.data.materials.new("white")
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.8, 0.8, 0.8, 1)
    bsdf.inputs["Specular"].default_value = 0.0
    bsdf.inputs["Roughness"].default_value = 1.0
    mesh = bpy.data.meshes.new("floor")
    mesh.from_pydata([(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)], [], [(0, 1, 2, 3)])
    mesh.materials.append(m)
    floor = bpy.data.objects.new("floor", mesh)
    scene.collection.objects.link(floor)
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    cam.location = (0, 0, 6)
    cam.data.lens = 35
    scene.collection.objects.link(cam)
    scene.camera = cam
    light = bpy.data.lights.new("light", {"point": "POINT", "spot": "SPOT", "sun": "SUN", "area": "AREA"}[kind])
    light.energy = {"point": 100.0, "spot": 100.0, "sun": 2.0, "area": 100.0}[kind]
    if kind in ("point", "spot"):
        light.shadow_soft_size = 0.0
    if kind == "spot":
        light.spot_size, light.spot_blend = math.radians(60), 0.0
    if kind == "sun":
        light.angle = 0.0
    if kind == "area":
        light.size = 0.5
    obj = bpy.data.objects.new("light", light)
    obj.location = (0.3, -0.2, 2.0)
    obj.rotation_euler = (math.radians(20), 0, 0) if kind == "sun" else (0, 0, 0)
    scene.collection.objects.link(obj)
    return scene


def cycles_direct(scene, path):
    scene.render.engine = "CYCLES"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", 256, False
    scene.cycles.max_bounces = scene.cycles.diffuse_bounces = 0
    scene.render.threads_mode, scene.render.threads = "FIXED", 2
    layer = scene.view_layers[0]
    layer.use_pass_diffuse_direct = layer.use_pass_diffuse_color = True
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR_MULTILAYER", "32"
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bounce.read_exr(path)
    return np.asarray(img["ViewLayer.DiffDir"]) * np.asarray(img["ViewLayer.DiffCol"])


def bounce_direct(scene, folder):
    scene.render.engine = "BOUNCE"
    scene.bounce_export_dir = folder
    scene.bounce.light_samples = 64
    bpy.ops.render.render()
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR_MULTILAYER", "32"
    path = os.path.join(folder, "bounce.exr")
    bpy.data.images["Render Result"].save_render(path)
    return np.asarray(bounce.read_exr(path)["ViewLayer.direct"])


def main():
    bounce_render.register()
    os.makedirs(OUT, exist_ok=True)
    for kind in ("point", "spot", "sun", "area"):
        folder = os.path.join(OUT, kind)
        os.makedirs(folder, exist_ok=True)
        c = cycles_direct(scene_with(kind), os.path.join(folder, "cycles.exr"))
        b = bounce_direct(scene_with(kind), folder)
        print(f"LIGHT {kind}: Cycles mean {c.mean():.5f}, bounce {b.mean():.5f}, bounce / Cycles {b.mean() / c.mean():.4f}", flush=True)


main()
