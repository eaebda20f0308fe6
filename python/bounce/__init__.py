"""bounce: one bounce of diffuse interreflection and ambient occlusion, made fast by an
irradiance cache. A scene file, its settings by name, renders as NumPy arrays.

    import bounce
    scene = bounce.Scene.load("scenes/cornell/cornell.json")
    scene["render.rays"] = 256
    img = scene.render(gi="cache")
    img["indirect"]          # (height, width, 3) float32, a view of the render's buffer
    img.stats["phases"]      # what --stats-json writes

docs/python.md has the whole interface.
"""

from ._bounce import (
    Cancelled,
    CancelToken,
    Error,
    Frames,
    Image,
    Scene,
    Session,
    __version__,
    params,
    read_exr,
)
from ._bounce import compare as _compare
from . import cache

__all__ = ["Scene", "Session", "Image", "Frames", "CancelToken", "Error", "Cancelled", "compare", "params", "read_exr", "cache", "__version__"]


def compare(test, reference, layer=None):
    """Per layer rmse, rel_rmse, relmse, mean_abs, max_abs and mean_ref of `test` against
    `reference` (each a bounce.Image or an EXR's path), as `bounce compare --json` prints them."""
    return _compare(test=test, reference=reference, layer=layer)
