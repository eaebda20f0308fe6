"""The rendered viewport's sessions (viewport.py), without a window: a light's edit re-shades
from the kept deep buffer and cache (its direct and bounce light scale with it), nothing
changed renders nothing, and an edit of the objects starts a new session."""

import json

import bpy
import numpy as np
import pytest

import bounce_render
import scenes
from bounce_render import settings, viewport


@pytest.fixture(autouse=True)
def addon():
    bounce_render.register()
    yield
    bounce_render.unregister()


def test_a_light_edit_reshades_and_an_object_edit_starts_anew(tmp_path):
    scene = scenes.cornell_box()
    scene.bounce.rays = 64
    vp = viewport.Viewport(str(tmp_path))
    sync = lambda only_lights=False: vp.sync(bpy.context.evaluated_depsgraph_get(), settings.changed_settings(scene.bounce, scene),
                                             None, only_lights)
    assert sync() == "rasterize"
    first = vp.image
    assert sync() is None  # nothing changed: nothing rendered
    bpy.data.lights["Ceiling"].energy *= 2
    assert sync(only_lights=True) == "reshade"
    second = vp.image
    # The records keep their light per light: the bounce light scales with the light, as the
    # direct light does, without a gather.
    assert second["direct"].mean() == pytest.approx(2 * first["direct"].mean(), rel=1e-5)
    assert second["indirect"].mean() == pytest.approx(2 * first["indirect"].mean(), rel=1e-4)
    # From the deep buffer and records the last render left: no camera ray, no gather ray.
    froms = {s["step"]: s.get("from") for s in second.stats["plan"]["steps"]}
    assert froms["visibility"] == "previous frame's" and froms["cache start"] == "previous frame's"
    assert second.stats["rays"]["camera"] == 0 and second.stats["gather_rays_per_pixel"] == 0
    session = vp.session
    bpy.data.objects["tall"].location.x += 0.1
    assert sync() == "rasterize" and vp.session is not session  # objects moved: a new session
    assert json.loads((tmp_path / "scene.json").read_text())["objects"]


def test_the_viewports_own_view_is_its_camera():
    from types import SimpleNamespace

    from mathutils import Euler, Matrix

    eye = Matrix.Translation((0, -5, 1)) @ Euler((np.radians(90), 0, 0)).to_matrix().to_4x4()  # looking along +Y
    camera = viewport.view_camera(SimpleNamespace(view_matrix=eye.inverted()), 50, 100, 50)
    assert camera["position"] == pytest.approx([0, 1, 5], abs=1e-5)  # Blender (x, y, z) -> bounce (x, z, -y)
    assert camera["look_at"] == pytest.approx([0, 1, 4], abs=1e-5)
    assert camera["up"] == pytest.approx([0, 1, 0], abs=1e-5)
    assert camera["fov"] == pytest.approx(np.degrees(2 * np.arctan(36 / 100 * 0.5)))
    assert camera["resolution"] == [100, 50]
