"""docs/examples/light_wedge.py, the notebook-style example, runs and says what light does."""

import importlib.util

import numpy as np
import pytest

from conftest import ROOT


def load_example():
    spec = importlib.util.spec_from_file_location("light_wedge", ROOT / "docs" / "examples" / "light_wedge.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_wedge_scales_with_the_light_and_plots(tmp_path):
    example = load_example()
    images = example.wedge(strengths=[0.5, 1.0, 2.0], resolution=(48, 48), rays=64)
    base = images[1.0]
    for s in (0.5, 2.0):
        # Direct and bounce light are linear in the light's strength.
        assert images[s]["direct"].mean() == pytest.approx(s * base["direct"].mean(), rel=1e-5)
        assert images[s]["indirect"].mean() == pytest.approx(s * base["indirect"].mean(), rel=2e-2)
    example.plot(images, tmp_path / "wedge.png")
    png = (tmp_path / "wedge.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 10000
    assert np.isfinite(base["beauty"]).all()
