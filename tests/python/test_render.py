"""A render through Python is the CLI's render of the same scene and options, bit for bit; its
layers are NumPy views; a shot keeps its records as `--frames` does."""

import json

import numpy as np
import pytest

import bounce
from conftest import CORNELL, ROLLING

SMALL = dict(resolution=[48, 48], spp=4, light_samples=4, rays=64)


def assert_same_layers(a, b):
    assert sorted(a.layers) == sorted(b.layers)
    for name in a.layers:
        assert np.array_equal(a[name], b[name]), name


def test_a_still_equals_the_cli_bit_for_bit(tmp_path, cli):
    scene = bounce.Scene.load(CORNELL)
    scene["render.min_spacing"] = 3
    py = scene.render(gi="cache", output=tmp_path / "py.exr", cache_out=tmp_path / "py.bic", **SMALL)
    cli("render", CORNELL, "-o", tmp_path / "cli.exr", "--cache-out", tmp_path / "cli.bic", "--gi", "cache", "--res", "48x48",
        "--spp", 4, "--light-samples", 4, "--rays", 64, "--set", "render.min_spacing=3", "--stats-json", tmp_path / "cli.json", "-q")
    assert_same_layers(bounce.read_exr(tmp_path / "py.exr"), bounce.read_exr(tmp_path / "cli.exr"))
    assert_same_layers(py, bounce.read_exr(tmp_path / "cli.exr"))
    cli_stats = json.loads((tmp_path / "cli.json").read_text())
    assert py.stats["records"] == cli_stats["records"] > 0
    assert py.stats["plan"] == cli_stats["plan"]
    assert bounce.cache.info(tmp_path / "py.bic")["records"] == bounce.cache.info(tmp_path / "cli.bic")["records"]


def test_a_layer_is_a_view_of_the_right_shape(tmp_path):
    img = bounce.Scene.load(CORNELL).render(gi="cache", **SMALL)
    indirect = img["indirect"]
    assert isinstance(indirect, np.ndarray)
    assert indirect.shape == (48, 48, 3) and indirect.dtype == np.float32
    assert not indirect.flags.owndata and np.shares_memory(indirect, img["indirect"])
    assert img["beauty"].shape == (48, 48, 4)
    assert img.window == (0, 48, 0, 48) and img.full_size == (48, 48)
    assert float(indirect.mean()) > 0
    mean = float(indirect.mean())
    del img  # the array keeps the image's buffer alive
    assert float(indirect.mean()) == mean
    with pytest.raises(KeyError, match="did you mean \"indirect\""):
        bounce.Scene.load(CORNELL).render(gi="cache", **SMALL)["indirectt"]


def test_settings_hold_for_later_renders_and_read_back(tmp_path):
    scene = bounce.Scene.load(CORNELL)
    assert scene["render.rays"] == bounce.Scene.load(CORNELL)["render.rays"] != 96
    scene["render.rays"] = 96
    scene["camera.resolution"] = [32, 24]
    assert scene["render.rays"] == 96 and scene["camera.resolution"] == [32, 24]
    assert scene.settings == ["render.rays=96", "camera.resolution=[32,24]"]
    img = scene.render(gi="brute", spp=1, light_samples=1)
    assert img["beauty"].shape == (24, 32, 4)
    assert img.stats["rays_per_gather"] == 96
    # Any value of the scene by its path, as --set sets it: a wedge of a light's brightness.
    assert scene["materials.light.emission"] == [17, 12, 4]
    scene["materials.light.emission"] = [34, 24, 8]
    brighter = scene.render(gi="none", spp=1, light_samples=1)
    scene["materials.light.emission"] = [17, 12, 4]
    dim = scene.render(gi="none", spp=1, light_samples=1)
    assert float(brighter["direct"].mean()) == pytest.approx(2 * float(dim["direct"].mean()), rel=1e-5)


def test_a_shot_equals_the_cli_frames(tmp_path, cli):
    scene = bounce.Scene.load(ROLLING)
    frames = list(scene.render_frames(range(1, 4), gi="cache", resolution=[40, 40], rays=48,
                                      output=tmp_path / "py.####.exr", cache_out=tmp_path / "py.####.bic"))
    assert len(frames) == 3
    cli("render", ROLLING, "--frames", "1-3", "-o", tmp_path / "cli.####.exr", "--cache-out", tmp_path / "cli.####.bic",
        "--gi", "cache", "--res", "40x40", "--rays", 48, "--stats-json", tmp_path / "cli.####.json", "-q")
    for f, img in zip(range(1, 4), frames):
        cli_img = bounce.read_exr(tmp_path / f"cli.{f:04d}.exr")
        assert_same_layers(img, cli_img)
        assert_same_layers(bounce.read_exr(tmp_path / f"py.{f:04d}.exr"), cli_img)
    # Records were carried from frame to frame, as the CLI carries them.
    for f, img in zip(range(2, 4), frames[1:]):
        cli_stats = json.loads((tmp_path / f"cli.{f:04d}.json").read_text())
        assert img.stats["records_reshaded"] + img.stats["records_kept"] > 0
        for key in ("records", "records_new", "records_reshaded", "records_kept", "records_moved"):
            assert img.stats[key] == cli_stats[key], key
    assert bounce.cache.info(tmp_path / "py.0003.bic")["records"] == bounce.cache.info(tmp_path / "cli.0003.bic")["records"]


def test_previews_reach_the_callback_and_the_frame_is_the_clis(tmp_path, cli):
    scene = bounce.Scene.load(CORNELL)
    seen = []

    def preview(p):
        seen.append((p.width, p.height, float(p["beauty"].mean())))

    scene.render(gi="cache", preview=preview, **SMALL)
    assert seen == []  # render.preview off: the plan calls for no preview
    img = scene.render(gi="cache", preview=preview, output=tmp_path / "py.exr", **{"render.preview": True}, **SMALL)
    assert seen and all(w == 48 and h == 48 for w, h, _ in seen) and seen[-1][2] > 0
    cli("render", CORNELL, "-o", tmp_path / "cli.exr", "--gi", "cache", "--preview", "--res", "48x48", "--spp", 4,
        "--light-samples", 4, "--rays", 64, "-q")
    assert_same_layers(img, bounce.read_exr(tmp_path / "cli.exr"))
