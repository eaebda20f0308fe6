"""bounce.compare and bounce.cache.* return what `bounce compare --json` and `bounce cache`
report, and write what they write."""

import json

import pytest

import bounce
from conftest import CORNELL

SMALL = dict(gi="cache", resolution=[40, 40], spp=2, light_samples=2, rays=48)


def test_compare_matches_the_cli(tmp_path, cli):
    scene = bounce.Scene.load(CORNELL)
    a = scene.render(output=tmp_path / "a.exr", **SMALL)
    b = scene.render(output=tmp_path / "b.exr", **dict(SMALL, rays=96))
    same = bounce.compare(a, a)
    assert same["indirect"]["rmse"] == 0 and same["indirect"]["rel_rmse"] == 0
    ours = bounce.compare(tmp_path / "b.exr", tmp_path / "a.exr")
    theirs = json.loads(cli("compare", tmp_path / "b.exr", tmp_path / "a.exr", "--json").stdout)
    assert ours == theirs
    assert ours["indirect"]["rel_rmse"] > 0
    assert bounce.compare(b, a, layer="indirect").keys() == {"indirect"}


def test_cache_tools_match_the_cli(tmp_path, cli):
    scene = bounce.Scene.load(CORNELL)
    scene.render(cache_out=tmp_path / "c.bic", **SMALL)
    info = bounce.cache.info(tmp_path / "c.bic")
    assert info == json.loads(cli("cache", "info", tmp_path / "c.bic", "--json").stdout)
    merged = bounce.cache.merge([tmp_path / "c.bic", tmp_path / "c.bic"], tmp_path / "m.bic")
    assert merged["records"] == info["records"]  # a cache merged with itself is itself
    kept = bounce.cache.filter(tmp_path / "c.bic", tmp_path / "f.bic", where="p.y > 274")
    dropped = bounce.cache.filter(tmp_path / "c.bic", tmp_path / "g.bic", where=["p.y > 274"], remove=True)
    assert kept["records"] + dropped["records"] == info["records"] and 0 < kept["records"] < info["records"]
    cli("cache", "filter", tmp_path / "c.bic", "-o", tmp_path / "cf.bic", "--where", "p.y > 274")
    assert bounce.cache.info(tmp_path / "cf.bic")["records"] == kept["records"]
    assert bounce.cache.export(tmp_path / "c.bic", tmp_path / "c.ply")["records"] == info["records"]
    assert (tmp_path / "c.ply").read_bytes().startswith(b"ply")
    with pytest.raises(bounce.Error, match="give a box, a sphere or a where term"):
        bounce.cache.filter(tmp_path / "c.bic", tmp_path / "h.bic")


def test_params_lists_the_table(cli):
    assert bounce.params() == json.loads(cli("params", "--json").stdout)
