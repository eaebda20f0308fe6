"""Bad input through Python raises one line (bounce.Error carries the CLI's message); a
render is cancelled by a token, a raising callback or Ctrl-C within a tile, and the scene
renders again afterwards as if nothing had happened."""

import math
import os
import signal
import threading

import numpy as np
import pytest

import bounce
from conftest import CORNELL

SMALL = dict(resolution=[32, 32], spp=1, light_samples=1, rays=32)
# Long enough that a cancel lands while it runs (about a second on this machine): brute force.
LONG = dict(gi="brute", resolution=[160, 160], spp=4, rays=256)


def one_line(error):
    text = str(error.value)
    assert text and "\n" not in text, text
    return text


def test_a_parameter_error_raises_the_cli_message(cli):
    scene = bounce.Scene.load(CORNELL)
    with pytest.raises(bounce.Error) as e:
        scene["render.rays"] = -1
    text = one_line(e)
    done = cli("render", CORNELL, "-o", "/tmp/never.exr", "--set", "render.rays=-1", check=False)
    assert done.returncode == 2
    # The same words after "error:", the place named the way each front end was given it.
    assert text.split("error: ", 1)[1] == done.stderr.strip().split("error: ", 1)[1] == "-1 is out of range [1, 1048576]"
    assert text.startswith('python: scene["render.rays"] = -1 (/render/rays): error:')
    assert isinstance(e.value, ValueError) and e.value.file == "python"
    # The scene did not take the bad value.
    assert scene["render.rays"] == bounce.Scene.load(CORNELL)["render.rays"]


@pytest.mark.parametrize("key, value, words", [
    ("render.rays", "many", "expected an integer"),
    ("render.rays", 1e39, "1e+39 is out of range"),
    ("render.min_spacing", math.nan, "not a number a scene file can hold"),
    ("render.min_spacing", math.inf, "not a number a scene file can hold"),
    ("render.rays", 2 ** 70, "beyond a 64-bit integer"),
    ("render.gi", "photons", "unknown value \"photons\""),
    ("render.rays", object(), "a object is not a value a scene file can hold"),
    ("camera.resolution", [64], "expected"),
    ("render.rays", np.zeros(3), "numpy.ndarray is not a value"),
    ("objects.99.material", "white", "index 99 is out of range"),
    ("materials.white.colour", 0.5, "unknown key \"colour\""),
])
def test_hostile_values_raise_one_line(key, value, words):
    scene = bounce.Scene.load(CORNELL)
    before = scene.settings
    with pytest.raises(bounce.Error) as e:
        scene[key] = value
    assert words in one_line(e)
    assert scene.settings == before


@pytest.mark.parametrize("call, words", [
    (lambda s: s.render(output=5), "a path is a str or an os.PathLike, not a int"),
    (lambda s: s.render(output="/tmp/x.png"), "OpenEXR"),
    (lambda s: s.render(gi="cache", output="/tmp/x.exr", cache_out=CORNELL), "cornell.json"),
    (lambda s: s.render(raysss=4), "did you mean \"rays\""),
    (lambda s: s.render(rays=math.nan), "not a number a scene file can hold"),
    (lambda s: s.render(regather="yes"), "expects True or False"),
    (lambda s: s.render(progress=3), "expects a callable"),
    (lambda s: s.render(cancel="stop"), "expects a bounce.CancelToken"),
    (lambda s: s.render(4), "keyword arguments only"),
    (lambda s: s.render(frame=math.inf), "expects a finite number"),
    (lambda s: s.render(cache_reuse="some"), "is \"strict\" or \"any\""),
    (lambda s: s.render(gi="brute", cache_out="/tmp/x.bic"), "only a --gi cache render makes a cache"),
    (lambda s: s.render(show="nothing"), "nothing"),
    (lambda s: s.render_frames("abc"), "expects frame numbers"),
    (lambda s: s.render_frames([1, 3]), "one after the other"),
    (lambda s: s.render_frames(range(1, 3), output="/tmp/f.exr"), "needs a #### frame pattern"),
    (lambda s: bounce.Scene.load(5), "a path is a str"),
    (lambda s: bounce.Scene.load("/nonexistent/scene.json"), "/nonexistent/scene.json"),
    (lambda s: bounce.Scene.load(CORNELL, frame=math.nan), "a frame must be a finite number"),
    (lambda s: bounce.Scene.from_dict([1, 2]), "expects a dict"),
    (lambda s: bounce.Scene.from_dict({"camera": {"fov": math.nan}}), "/camera/fov"),
    (lambda s: bounce.Scene.from_dict({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]}, "objects": [{"type": "mesh", "file": "../../../etc/passwd"}]}), "/objects/0"),
    (lambda s: bounce.compare(test="/nonexistent.exr", reference="/nonexistent.exr"), "/nonexistent.exr"),
    (lambda s: bounce.cache.info("/nonexistent.bic"), "/nonexistent.bic"),
    (lambda s: bounce.cache.filter(str(CORNELL), "/tmp/f.bic", sphere=(0, 0, 0, -1)), "the radius must be > 0"),
    (lambda s: bounce.cache.merge(["/a.bic"], str(CORNELL)), "written as a .bic file"),
])
def test_hostile_calls_raise_one_line(call, words):
    scene = bounce.Scene.load(CORNELL)
    with pytest.raises((bounce.Error, KeyError)) as e:
        call(scene)
    assert words in str(e.value), str(e.value)
    assert "\n" not in str(e.value)


def test_a_token_cancels_within_a_tile_and_the_scene_renders_again(tmp_path):
    scene = bounce.Scene.load(CORNELL)
    reports = []
    token = bounce.CancelToken()

    def progress(phase, done, total, elapsed):
        reports.append((phase, done, total))
        if phase == "gather":
            token.cancel()  # at the first report of the gathering pass (its first tile done)

    with pytest.raises(bounce.Cancelled):
        scene.render(output=tmp_path / "cancelled.exr", progress=progress, cancel=token, **LONG)
    assert token.cancelled
    assert not (tmp_path / "cancelled.exr").exists()  # nothing written
    # It stopped inside the gathering pass, a tile or two after the cancel: never reached shading.
    phase, done, total = reports[-1]
    assert phase == "gather" and done < total
    assert "shading" not in [r[0] for r in reports]
    # A cancelled scene renders again, the same image as a fresh scene's.
    again = scene.render(**SMALL)
    fresh = bounce.Scene.load(CORNELL).render(**SMALL)
    assert np.array_equal(again["beauty"], fresh["beauty"])


def test_a_raising_callback_cancels_and_its_exception_reaches_the_script():
    scene = bounce.Scene.load(CORNELL)

    def progress(*_):
        raise RuntimeError("the artist pressed Esc")

    with pytest.raises(RuntimeError, match="the artist pressed Esc"):
        scene.render(progress=progress, **LONG)


def test_ctrl_c_stops_the_render_with_keyboard_interrupt():
    scene = bounce.Scene.load(CORNELL)
    started = threading.Event()
    # SIGINT from another thread, as a terminal sends it: the render's poll sees it (the
    # callback only tells the thread when the render is under way).
    threading.Thread(target=lambda: started.wait(60) and os.kill(os.getpid(), signal.SIGINT), daemon=True).start()
    with pytest.raises(KeyboardInterrupt):
        scene.render(progress=lambda *_: started.set(), **LONG)
    assert np.isfinite(scene.render(**SMALL)["beauty"]).all()
