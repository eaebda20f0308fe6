"""The add-on in Debian's Blender, headless (docs/blender.md): a Cornell box built by script
renders through the add-on to the image the CLI renders from the scene the add-on exported,
bit for bit, with its passes; a collection instanced 1000 times exports as 1000 placements of
one prototype; a cutout leaf renders with holes; a three-frame animation is the CLI's
`--frames 1-3`; Esc cancels."""

import json
import math
import os
import subprocess

import bpy
import numpy as np
import pytest

import bounce
import bounce_render
import scenes

BINARY = os.environ.get("BOUNCE_BINARY", os.path.join(os.path.dirname(__file__), "..", "..", "build", "bounce"))


@pytest.fixture(autouse=True)
def addon():
    bounce_render.register()
    yield
    bounce_render.unregister()


def render(scene, folder):
    """F12 through the add-on; the render result saved as a 32-bit multilayer EXR, read back."""
    scene.bounce_export_dir = str(folder)
    bpy.ops.render.render()
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR_MULTILAYER", "32"
    path = str(folder / "blender.exr")
    bpy.data.images["Render Result"].save_render(path)
    return bounce.read_exr(path)


def cli(*args):
    done = subprocess.run([BINARY, *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done


def blender_layer(image, name):
    """A pass of Blender's EXR (layer "ViewLayer.<pass>"), rows as bounce's."""
    return image[f"ViewLayer.{name}"]


def test_the_cornell_box_renders_as_the_cli_renders_its_export(tmp_path):
    scene = scenes.cornell_box()
    scene.bounce.rays = 64
    ours = render(scene, tmp_path)
    cli("render", tmp_path / "scene.json", "-o", tmp_path / "cli.exr", "-q")
    theirs = bounce.read_exr(tmp_path / "cli.exr")
    assert np.array_equal(blender_layer(ours, "Combined"), theirs["beauty"])
    for layer in ("direct", "indirect", "albedo"):
        assert np.array_equal(blender_layer(ours, layer), theirs[layer]), layer
    # Blender stores a depth that saw nothing as the largest float, bounce as infinity.
    depth = theirs["depth"][..., 0]
    assert np.array_equal(blender_layer(ours, "Depth")[..., 0], np.where(np.isinf(depth), np.finfo(np.float32).max, depth))
    assert np.isfinite(depth).mean() > 0.3
    # The room is lit, and its bounce light is there: red and green bleed onto the white boxes.
    assert theirs["indirect"].mean() > 0.01 and theirs["direct"].mean() > 0.01
    doc = json.loads((tmp_path / "scene.json").read_text())
    assert doc["lights"][0]["type"] == "quad" and len(doc["objects"]) == 7


def test_a_collection_instanced_1000_times_is_1000_placements_of_one_prototype(tmp_path):
    scene = scenes.empty_scene(32, 32)
    leaf_collection = bpy.data.collections.new("pebble")
    scenes.mesh_object("pebble", scenes.CUBE, scenes.CUBE_FACES, scenes.material("stone", (0.5, 0.5, 0.5)),
                       scale=(0.1, 0.1, 0.1), collection=leaf_collection)
    for i in range(1000):
        inst = bpy.data.objects.new(f"pebble.{i}", None)
        inst.instance_type, inst.instance_collection = "COLLECTION", leaf_collection
        inst.location = (i % 40 - 20) * 0.3, (i // 40) * 0.3, 0
        scene.collection.objects.link(inst)
    scenes.camera((0, -8, 6), (55, 0, 0))
    scene.world = bpy.data.worlds.new("sky")
    scene.world.color = (0.5, 0.5, 0.5)
    scene.bounce.gi = "none"
    img = render(scene, tmp_path)
    doc = json.loads((tmp_path / "scene.json").read_text())
    prototypes = [o for o in doc["objects"] if o.get("prototype")]
    instancers = [o for o in doc["objects"] if "instances" in o]
    assert len(prototypes) == 1 and len(instancers) == 1 and len(doc["objects"]) == 2
    assert len(instancers[0]["instances"]["transforms"]) == 1000
    assert len(list(tmp_path.glob("*.ply"))) == 1
    assert blender_layer(img, "Combined")[..., 3].mean() > 0.05  # pebbles seen


def test_particle_and_geometry_node_instances_are_placements(tmp_path):
    scene = scenes.scattered()
    scene.bounce.gi = "none"
    render(scene, tmp_path)
    doc = json.loads((tmp_path / "scene.json").read_text())
    placements = sorted(len(o["instances"]["transforms"]) for o in doc["objects"] if "instances" in o)
    assert placements == [20, 50]  # the grid's 5 x 4 and the particle system's 50
    assert sum(1 for o in doc["objects"] if o.get("prototype")) == 2
    assert [o["name"] for o in doc["objects"] if "file" in o and not o.get("prototype")] == ["ground"]


def test_the_camera_lens_depth_of_field_and_an_environment_export(tmp_path):
    scene = scenes.cornell_box()
    scene.render.resolution_x = 96  # wider than tall: the sensor's width spans the image's
    cam = scene.camera.data
    cam.dof.use_dof, cam.dof.aperture_fstop, cam.dof.focus_distance = True, 2.8, 3.5
    image = bpy.data.images.new("env", 16, 8, float_buffer=True)
    image.pixels.foreach_set(np.full(16 * 8 * 4, 0.25, np.float32))
    image.filepath_raw, image.file_format = str(tmp_path / "env.exr"), "OPEN_EXR"
    image.save()
    scene.world = bpy.data.worlds.new("env")
    scene.world.use_nodes = True
    env = scene.world.node_tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = image
    scene.world.node_tree.links.new(env.outputs["Color"], scene.world.node_tree.nodes["Background"].inputs["Color"])
    scene.bounce.gi = "none"
    render(scene, tmp_path)
    doc = json.loads((tmp_path / "scene.json").read_text())
    hfov = 2 * math.atan(36 / (2 * 35))
    assert doc["camera"]["fov"] == pytest.approx(math.degrees(2 * math.atan(math.tan(hfov / 2) * 64 / 96)))
    assert doc["camera"]["resolution"] == [96, 64]
    assert doc["camera"]["aperture"] == pytest.approx(0.035 / 2.8) and doc["camera"]["focus_distance"] == pytest.approx(3.5)
    sky = [light for light in doc["lights"] if light["type"] == "sky"]
    assert sky and sky[0]["texture"] == str(tmp_path / "env.exr") and sky[0]["rotation"] == 90.0


def test_a_cutout_leaf_renders_with_holes(tmp_path):
    scene = scenes.empty_scene(64, 64)
    image = scenes.checker_alpha_image(str(tmp_path / "cutout.png"))
    leaf = scenes.material("leaf", (0.8, 0.1, 0.1), alpha_image=image)
    quad = [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)]
    scenes.mesh_object("leaf", quad, [(0, 1, 2, 3)], leaf, uvs=True)
    scenes.mesh_object("wall", [(-3, 2, -3), (3, 2, -3), (3, 2, 3), (-3, 2, 3)], [(0, 1, 2, 3)], scenes.material("wall", (0.1, 0.7, 0.1)))
    scenes.camera((0, -4, 0), (90, 0, 0), lens=50)
    scene.world = bpy.data.worlds.new("sky")
    scene.world.color = (1, 1, 1)
    scene.bounce.gi = "none"
    rgb = blender_layer(render(scene, tmp_path), "Combined")[..., :3]
    doc = json.loads((tmp_path / "scene.json").read_text())
    assert doc["materials"]["leaf"]["alpha_mode"] == "mask" and doc["materials"]["leaf"]["opacity_texture"].endswith("cutout.png")
    centre = rgb[16:48, 16:48]
    red = (centre[..., 0] > 2 * centre[..., 1]).mean()
    green = (centre[..., 1] > 2 * centre[..., 0]).mean()
    # The leaf's opaque cells and, through its holes, the green wall: about half each.
    assert 0.3 < red < 0.7 and 0.3 < green < 0.7, (red, green)


def test_three_frames_render_as_one_shot_equal_to_the_cli_frames(tmp_path):
    scene = scenes.cornell_box()
    scene.bounce.rays = 48
    tall = bpy.data.objects["tall"]
    for f, x in ((1, -0.35), (3, -0.15)):
        tall.location.x = x
        tall.keyframe_insert("location", frame=f)
    scene.frame_start, scene.frame_end = 1, 3
    scene.bounce_export_dir = str(tmp_path)
    scene.render.filepath = str(tmp_path / "blender.")
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR_MULTILAYER", "32"
    bpy.ops.render.render(animation=True)
    shot = tmp_path / "shot" / "scene.json"
    doc = json.loads(shot.read_text())
    assert doc["animation"]["frames"] == [1, 3] and "keys" in json.dumps([o for o in doc["objects"] if o["name"] == "tall"])
    cli("render", shot, "--frames", "1-3", "-o", tmp_path / "cli.####.exr", "--stats-json", tmp_path / "cli.####.json", "-q")
    for f in (1, 2, 3):
        ours = bounce.read_exr(tmp_path / f"blender.{f:04d}.exr")
        theirs = bounce.read_exr(tmp_path / f"cli.{f:04d}.exr")
        assert np.array_equal(blender_layer(ours, "Combined"), theirs["beauty"]), f
        assert np.array_equal(blender_layer(ours, "indirect"), theirs["indirect"]), f
    # Records were carried from frame to frame (the CLI's own count, for the same frames).
    assert json.loads((tmp_path / "cli.0002.json").read_text())["records_reshaded"] > 0


def test_esc_cancels(tmp_path, monkeypatch):
    scene = scenes.cornell_box()
    scene.bounce.rays = 1024
    scene.render.resolution_x = scene.render.resolution_y = 256
    calls = []

    def pressed(engine):
        calls.append(1)
        return True

    monkeypatch.setattr(bounce_render.engine, "esc_pressed", pressed)
    scene.bounce_export_dir = str(tmp_path)
    bpy.ops.render.render()
    assert calls, "the render never asked whether Esc was pressed"
    # Cancelled at the first progress report: the scene was exported, no pixel was written.
    assert (tmp_path / "scene.json").exists()
    assert len(calls) == 1
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR_MULTILAYER", "32"
    with pytest.raises(RuntimeError, match="could not be saved"):  # Blender has no image to save
        bpy.data.images["Render Result"].save_render(str(tmp_path / "cancelled.exr"))


def test_what_cannot_be_exported_is_reported_and_bad_scenes_raise_one_line(tmp_path, capfd):
    scene = scenes.cornell_box()
    bpy.data.objects["Ceiling"].data.shape = "DISK"
    bsdf = bpy.data.materials["red"].node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Subsurface"].default_value = 0.5
    bpy.data.objects["short"].visible_camera = False
    bpy.data.objects["tall"].is_holdout = True
    spot = bpy.data.lights.new("Spot", "SPOT")
    spot.energy, spot.spot_size, spot.shadow_soft_size = 10.0, math.radians(60), 0.0
    spot_object = bpy.data.objects.new("Spot", spot)
    spot_object.location = (0, 0, 1.5)
    scene.collection.objects.link(spot_object)
    render(scene, tmp_path)
    out = capfd.readouterr().out
    assert "light Ceiling: a disk rendered as a rectangle of the same area" in out
    # Cycles 3.4's spot falls off as cos of the angle from its axis (bench/peers/light_units.py).
    lights = {l["name"]: l for l in json.loads((tmp_path / "scene.json").read_text())["lights"]}
    assert lights["Spot"]["cosine_power"] == 1
    assert "light Spot" not in out
    assert "material red: Subsurface is not read" in out
    doc = json.loads((tmp_path / "scene.json").read_text())
    objects = {o["name"]: o for o in doc["objects"]}
    assert objects["short"]["visible_to"] == {"camera": False, "shadows": True, "indirect": True, "reflections": True}
    assert objects["tall"]["matte"] is True
    # A scene without a camera, and one without a mesh: Blender's error, one line, no crash.
    bpy.context.scene.camera = None
    with pytest.raises(RuntimeError, match="no camera"):  # Blender refuses it before the engine runs
        bpy.ops.render.render()
    scenes.empty_scene()
    scenes.camera((0, -4, 0), (90, 0, 0))
    with pytest.raises(RuntimeError, match="bounce: nothing to render: the scene has no mesh"):
        bpy.ops.render.render()
    # An export folder that cannot be made: one line, no traceback.
    scenes.cornell_box().bounce_export_dir = "/proc/bounce-cannot-be-here"
    with pytest.raises(RuntimeError, match="bounce: .*/proc/bounce-cannot-be-here"):
        bpy.ops.render.render()
    # A setting the table refuses never reaches a render: Blender's property keeps it in range.
    scene = bpy.context.scene
    scene.bounce.rays = -5
    assert scene.bounce.rays == 1
