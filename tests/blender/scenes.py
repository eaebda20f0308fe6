"""Scenes the add-on's tests build in Blender by script: a Cornell box, a collection instanced
many times, a cutout leaf."""

import math

import bpy
import numpy as np

CUBE = [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1), (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]
CUBE_FACES = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]


def empty_scene(width=64, height=64):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "BOUNCE"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
    return scene


def material(name, colour, alpha_image=None, emission=None):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1)
    bsdf.inputs["Specular"].default_value = 0.0
    bsdf.inputs["Roughness"].default_value = 1.0
    if emission is not None:
        bsdf.inputs["Emission"].default_value = (*emission, 1)
    if alpha_image is not None:
        tex = m.node_tree.nodes.new("ShaderNodeTexImage")
        tex.image = alpha_image
        m.node_tree.links.new(tex.outputs["Alpha"], bsdf.inputs["Alpha"])
        m.blend_method = "CLIP"
    return m


def mesh_object(name, verts, faces, mat, location=(0, 0, 0), scale=(1, 1, 1), rotation=(0, 0, 0), collection=None, uvs=False):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    if uvs:
        layer = mesh.uv_layers.new()
        for poly in mesh.polygons:
            for k, li in enumerate(poly.loop_indices):
                layer.data[li].uv = [(0, 0), (1, 0), (1, 1), (0, 1)][k % 4]
    mesh.materials.append(mat)
    obj = bpy.data.objects.new(name, mesh)
    obj.location, obj.scale, obj.rotation_euler = location, scale, rotation
    (collection or bpy.context.scene.collection).objects.link(obj)
    return obj


def camera(location, rotation_deg, lens=35):
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location, cam.rotation_euler = location, [math.radians(a) for a in rotation_deg]
    cam.data.lens = lens
    bpy.context.scene.collection.objects.link(cam)
    bpy.context.scene.camera = cam
    return cam


def area_light(location, size, power):
    data = bpy.data.lights.new("Ceiling", "AREA")
    data.size, data.energy = size, power
    light = bpy.data.objects.new("Ceiling", data)
    light.location = location
    bpy.context.scene.collection.objects.link(light)
    return light


def cornell_box():
    """The Cornell box in metres, Z up: a 2 m room open towards -Y, a ceiling light, two boxes."""
    scene = empty_scene()
    white, red, green = material("white", (0.73, 0.71, 0.68)), material("red", (0.63, 0.065, 0.05)), material("green", (0.14, 0.45, 0.091))
    quad = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
    mesh_object("floor", quad, [(0, 1, 2, 3)], white)
    mesh_object("ceiling", quad, [(0, 3, 2, 1)], white, location=(0, 0, 2))
    mesh_object("back", quad, [(0, 1, 2, 3)], white, location=(0, 1, 1), rotation=(math.radians(90), 0, 0))
    mesh_object("left", quad, [(0, 1, 2, 3)], red, location=(-1, 0, 1), rotation=(0, math.radians(90), 0))
    mesh_object("right", quad, [(0, 3, 2, 1)], green, location=(1, 0, 1), rotation=(0, math.radians(90), 0))
    mesh_object("tall", CUBE, CUBE_FACES, white, location=(-0.35, 0.3, 0.6), scale=(0.3, 0.3, 0.6), rotation=(0, 0, math.radians(20)))
    mesh_object("short", CUBE, CUBE_FACES, white, location=(0.35, -0.3, 0.3), scale=(0.3, 0.3, 0.3), rotation=(0, 0, math.radians(-18)))
    area_light((0, 0, 1.98), 0.5, 60)
    camera((0, -3.9, 1), (90, 0, 0), lens=35)
    return scene


def checker_alpha_image(path, n=64, cells=4):
    """An RGBA PNG: opaque and transparent cells (a leaf card's cutout)."""
    img = bpy.data.images.new("cutout", n, n, alpha=True)
    y, x = np.mgrid[0:n, 0:n]
    alpha = (((x * cells) // n + (y * cells) // n) % 2).astype(np.float32)
    rgba = np.stack([np.ones_like(alpha), np.ones_like(alpha), np.ones_like(alpha), alpha], -1)
    img.pixels.foreach_set(rgba.ravel())
    img.filepath_raw = path
    img.file_format = "PNG"
    img.save()
    return img


def scattered():
    """A pebble scattered by a hair particle system (50) and by geometry nodes (5 x 4 grid)."""
    scene = empty_scene(32, 32)
    stone = material("stone", (0.5, 0.5, 0.5))
    hidden = bpy.data.collections.new("hidden")  # the pebble itself is in no scene collection
    pebble = mesh_object("pebble", CUBE, CUBE_FACES, stone, scale=(0.05, 0.05, 0.05), collection=hidden)
    ground = mesh_object("ground", [(-2, -2, 0), (2, -2, 0), (2, 2, 0), (-2, 2, 0)], [(0, 1, 2, 3)], stone)
    particles = ground.modifiers.new("scatter", "PARTICLE_SYSTEM").particle_system.settings
    particles.type, particles.count, particles.render_type, particles.instance_object = "HAIR", 50, "OBJECT", pebble
    holder = mesh_object("grid", [(0, 0, 0)], [], stone, location=(0, 0, 1))
    tree = bpy.data.node_groups.new("scatter", "GeometryNodeTree")
    holder.modifiers.new("grid", "NODES").node_group = tree
    tree.outputs.new("NodeSocketGeometry", "Geometry")
    out, points = tree.nodes.new("NodeGroupOutput"), tree.nodes.new("GeometryNodeMeshGrid")
    points.inputs["Vertices X"].default_value, points.inputs["Vertices Y"].default_value = 5, 4
    on_points, info = tree.nodes.new("GeometryNodeInstanceOnPoints"), tree.nodes.new("GeometryNodeObjectInfo")
    info.inputs["Object"].default_value = pebble
    tree.links.new(points.outputs["Mesh"], on_points.inputs["Points"])
    tree.links.new(info.outputs["Geometry"], on_points.inputs["Instance"])
    tree.links.new(on_points.outputs["Instances"], out.inputs["Geometry"])
    camera((0, -6, 4), (55, 0, 0))
    scene.world = bpy.data.worlds.new("sky")
    scene.world.color = (0.5, 0.5, 0.5)
    return scene
