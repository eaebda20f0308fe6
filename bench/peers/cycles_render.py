"""Inside Blender (bench/peers/cycles runs it): builds a bounce scene file's set in Blender and
renders it with Cycles, one diffuse bounce, no denoiser, the passes that make the diffuse
indirect light; prints one JSON line with the times.

  blender -b --factory-startup -P bench/peers/cycles_render.py -- SCENE.json OUT.exr SAMPLES THREADS WxH SEED

The set: quads, spheres and mesh files (OBJ through Blender's importer) with their transforms,
each material's colour (and colour texture) as a Diffuse BSDF plus its emission, the camera
(position, look_at, up, vertical fov) and point, spot, distant, quad and sky lights with the
units the add-on's export uses the other way round (docs/blender.md). Bounce is Y-up, Blender
Z-up: (x, y, z) -> (x, -z, y)."""

import json
import math
import os
import sys
import time

import bpy
from mathutils import Matrix, Vector

TO_BLENDER = Matrix(((1, 0, 0, 0), (0, 0, -1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))


def vec(v):
    return (TO_BLENDER @ Vector((*v, 1))).xyz


def direction(v):
    return (TO_BLENDER.to_3x3() @ Vector(v)).normalized()


def colour(v, default=0.7):
    v = default if v is None else v
    return (v, v, v) if isinstance(v, (int, float)) else tuple(v[:3])


def material(name, m, folder):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*colour(m.get("color")), 1)
    if "color_texture" in m:
        tex = nodes.new("ShaderNodeTexImage")
        tex.image = bpy.data.images.load(os.path.join(folder, m["color_texture"]))
        tex.image.colorspace_settings.name = "Non-Color"  # bounce reads textures as stored
        mix = nodes.new("ShaderNodeMixRGB")
        mix.blend_type, mix.inputs["Fac"].default_value = "MULTIPLY", 1.0
        mix.inputs["Color1"].default_value = (*colour(m.get("color"), 1.0), 1)
        links.new(tex.outputs["Color"], mix.inputs["Color2"])
        links.new(mix.outputs["Color"], diffuse.inputs["Color"])
    shader = diffuse.outputs["BSDF"]
    if "emission" in m:
        emit = nodes.new("ShaderNodeEmission")
        emit.inputs["Color"].default_value = (*colour(m["emission"], 0), 1)
        add = nodes.new("ShaderNodeAddShader")
        links.new(shader, add.inputs[0])
        links.new(emit.outputs["Emission"], add.inputs[1])
        shader = add.outputs["Shader"]
    links.new(shader, out.inputs["Surface"])
    return mat


def transform_of(o):
    t = o.get("transform", {})
    if "matrix" in t:
        return Matrix([t["matrix"][4 * r:4 * r + 4] for r in range(4)])
    m = Matrix.Identity(4)
    if "translate" in t:
        m = m @ Matrix.Translation(t["translate"])
    if "rotate" in t:
        deg, *axis = t["rotate"]
        m = m @ Matrix.Rotation(math.radians(deg), 4, Vector(axis))
    if "scale" in t:
        s = t["scale"]
        s = [s] * 3 if isinstance(s, (int, float)) else s
        m = m @ Matrix.Diagonal((*s, 1))
    return m


def add_object(o, mats, folder):
    mat = mats.get(o.get("material"))
    kind = o.get("type", "mesh" if "file" in o else None)
    if kind == "quad":
        mesh = bpy.data.meshes.new(o["name"])
        mesh.from_pydata([vec(v) for v in o["vertices"]], [], [(0, 1, 2, 3)])
        obj = bpy.data.objects.new(o["name"], mesh)
        bpy.context.scene.collection.objects.link(obj)
        objs = [obj]
    elif kind == "sphere":
        bpy.ops.mesh.primitive_uv_sphere_add(segments=128, ring_count=64, radius=o.get("radius", 1), location=vec(o.get("center", [0, 0, 0])))
        objs = [bpy.context.active_object]
        bpy.ops.object.shade_smooth()
    elif kind == "mesh":
        before = set(bpy.data.objects)
        path = os.path.join(folder, o["file"])
        if path.lower().endswith(".obj"):
            bpy.ops.import_scene.obj(filepath=path, axis_forward="-Z", axis_up="Y")
        elif path.lower().endswith((".gltf", ".glb")):
            bpy.ops.import_scene.gltf(filepath=path)
        else:
            bpy.ops.import_mesh.ply(filepath=path)
        objs = [x for x in bpy.data.objects if x not in before and x.type == "MESH"]
        # OBJ and glTF importers turn Y-up into Z-up themselves; the PLY importer reads the
        # coordinates as they are (bounce's Y-up).
        turned = path.lower().endswith((".obj", ".gltf", ".glb"))
        m = TO_BLENDER @ transform_of(o) @ (TO_BLENDER.inverted() if turned else Matrix.Identity(4))
        for x in objs:
            x.matrix_world = m @ x.matrix_world
    else:
        sys.exit(f"cycles_render: object {o.get('name')}: type {kind} is not built")
    for x in objs:
        if mat is not None:
            x.data.materials.clear()
            x.data.materials.append(mat)
    return objs


def add_light(l, folder):
    kind = l["type"]
    c = colour(l.get("color"), 1.0)
    k = l.get("intensity", 1.0)
    if kind == "sky":
        world = bpy.data.worlds.new("sky")
        world.use_nodes = True
        bg = world.node_tree.nodes["Background"]
        bg.inputs["Color"].default_value = (*c, 1)
        bg.inputs["Strength"].default_value = k
        if "texture" in l:
            env = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
            env.image = bpy.data.images.load(os.path.join(folder, l["texture"]))
            world.node_tree.links.new(env.outputs["Color"], bg.inputs["Color"])
        bpy.context.scene.world = world
        return
    types = {"point": "POINT", "spot": "SPOT", "distant": "SUN", "quad": "AREA"}
    data = bpy.data.lights.new(l.get("name", kind), types[kind])
    data.color = c
    obj = bpy.data.objects.new(data.name, data)
    obj.visible_camera = False  # bounce's lights are not seen by camera rays
    bpy.context.scene.collection.objects.link(obj)
    if kind in ("point", "spot"):
        data.energy, data.shadow_soft_size = k * 4 * math.pi, 0.0
        obj.location = vec(l["position"])
    if kind in ("spot", "distant"):
        d = direction(l.get("direction", [0, -1, 0]))
        obj.rotation_euler = d.to_track_quat("-Z", "Y").to_euler()
    if kind == "spot":
        outer = l.get("cone_angle", 30) + l.get("cone_falloff", 5)
        data.spot_size, data.spot_blend = math.radians(2 * outer), l.get("cone_falloff", 5) / outer
    if kind == "distant":
        data.energy, data.angle = k, 0.0
    if kind == "quad":
        u, v = Vector(l["edge_u"]), Vector(l["edge_v"])
        data.shape, data.size, data.size_y = "RECTANGLE", v.length, u.length
        n = direction(list(u.cross(v)))
        obj.location = vec([a + 0.5 * (b + e) for a, b, e in zip(l["corner"], l["edge_u"], l["edge_v"])])
        obj.rotation_euler = n.to_track_quat("-Z", "Y").to_euler()
        data.energy = k * 4 * u.cross(v).length * max(c)  # Cycles: radiance = power / (4 area), measured
        data.color = tuple(x / max(c) for x in c)


def build(doc, folder, res):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    mats = {name: material(name, m, folder) for name, m in doc.get("materials", {}).items()}
    for o in doc["objects"]:
        add_object(o, mats, folder)
    for l in doc.get("lights", []):
        add_light(l, folder)
    cam = doc["camera"]
    data = bpy.data.cameras.new("camera")
    obj = bpy.data.objects.new("camera", data)
    scene.collection.objects.link(obj)
    pos, at, up = vec(cam["position"]), vec(cam["look_at"]), direction(cam.get("up", [0, 1, 0]))
    forward = (at - pos).normalized()
    right = forward.cross(up).normalized()
    true_up = right.cross(forward)
    basis = Matrix.Identity(4)  # the camera looks along its -Z with +Y up
    basis.col[0].xyz, basis.col[1].xyz, basis.col[2].xyz, basis.col[3].xyz = right, true_up, -forward, pos
    obj.matrix_world = basis
    data.sensor_fit, data.angle_y = "VERTICAL", math.radians(cam["fov"])
    data.clip_start, data.clip_end = 1e-4, 1e9  # bounce's camera sees everything in front of it
    scene.camera = obj
    w, h = res
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
    return scene


def main():
    args = sys.argv[sys.argv.index("--") + 1:]
    scene_file, out, samples, threads, res, seed = args[0], args[1], int(args[2]), int(args[3]), args[4], int(args[5])
    doc = json.load(open(scene_file))
    t0 = time.time()
    scene = build(doc, os.path.dirname(os.path.abspath(scene_file)), [int(x) for x in res.split("x")])
    built = time.time() - t0
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device, c.samples, c.seed, c.use_denoising = "CPU", samples, seed, False
    c.use_adaptive_sampling = False
    c.max_bounces, c.diffuse_bounces, c.glossy_bounces, c.transmission_bounces = 2, 1, 0, 0
    c.volume_bounces, c.transparent_max_bounces = 0, 0
    c.caustics_reflective = c.caustics_refractive = False
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.pixel_filter_type, c.filter_width = "BOX", 1.0  # bounce's pixel: its subsamples averaged
    scene.render.threads_mode, scene.render.threads = "FIXED", threads
    layer = scene.view_layers[0]
    layer.use_pass_diffuse_indirect = layer.use_pass_diffuse_color = layer.use_pass_diffuse_direct = True
    scene.view_settings.view_transform = "Standard"
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR_MULTILAYER", "32"
    scene.render.filepath = out
    t1 = time.process_time(), time.time()
    bpy.ops.render.render(write_still=True)
    cpu, wall = time.process_time() - t1[0], time.time() - t1[1]
    print("CYCLES_TIMES " + json.dumps({"build_s": built, "render_cpu_s": cpu, "render_wall_s": wall, "samples": samples}))


main()
