"""bounce.Session, the lighting tool's engine from Python: an edit re-renders what it needs
from the deep buffer and cache the last render kept, and bad edits raise one line."""

import numpy as np
import pytest

import bounce
from conftest import CORNELL


def test_an_edit_rerenders_only_what_it_needs(tmp_path):
    s = bounce.Session(scene=CORNELL, out_dir=tmp_path)
    s["camera.resolution"] = [40, 40]
    s["render.rays"] = 48
    assert s.pending == "rasterize"
    first = s.render()
    assert first["beauty"].shape == (40, 40, 4) and s.pending is None
    assert s.edit("render.min_spacing", 3)["needs"] == "regather"
    assert s.edit("materials.light.emission", [34, 24, 8])["needs"] == "reshade"
    assert s.pending == "regather"  # the most any edit since the last render needs
    second = s.render()
    assert second.stats["rays"]["camera"] == 0  # the deep buffer was kept
    assert second["direct"].mean() == pytest.approx(2 * first["direct"].mean(), rel=1e-5)
    s["materials.light.emission"] = [17, 12, 4]
    third = s.render(action="reshade")
    assert np.array_equal(third["direct"], s.render(action="reshade")["direct"])


def test_bad_sessions_and_edits_raise_one_line(tmp_path):
    with pytest.raises(bounce.Error, match="a path is a str"):
        bounce.Session(scene=5, out_dir=tmp_path)
    with pytest.raises(bounce.Error, match="give scene= and out_dir="):
        bounce.Session(scene=CORNELL)
    with pytest.raises(bounce.Error, match="threads"):
        bounce.Session(scene=CORNELL, out_dir=tmp_path, threads=-1)
    s = bounce.Session(scene=CORNELL, out_dir=tmp_path)
    for key, value, words in [("render.rays", -1, "out of range"), ("render.min_spacing", float("nan"), "not a number"),
                              ("lights.9.intensity", 1, "lights"), ("render.gi", "photons", "photons")]:
        with pytest.raises(bounce.Error, match=words) as e:
            s[key] = value
        assert "\n" not in str(e.value)
    with pytest.raises(bounce.Error, match="action"):
        s.render(action="paint")


def test_a_raising_callback_stops_a_session_render_and_it_renders_again(tmp_path):
    s = bounce.Session(scene=CORNELL, out_dir=tmp_path)
    s["camera.resolution"] = [96, 96]

    def progress(*_):
        raise RuntimeError("stop")

    with pytest.raises(RuntimeError, match="stop"):
        s.render(progress=progress)
    assert s.status()["state"] == "cancelled"
    s["camera.resolution"] = [24, 24]
    assert s.render()["beauty"].shape == (24, 24, 4)
