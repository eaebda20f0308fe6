"""The irradiance cache's files (.bic), as `bounce cache info|merge|filter|export` treats them."""

from . import _bounce


def info(path):
    """Counts, bounds, parameters, radius histogram and memory of a cache file, as a dict."""
    return _bounce.cache_info(path=path)


def merge(inputs, output, force=False):
    """Merges the cache files `inputs` without duplicates into `output` (.bic); returns its counts.
    force=True merges caches of different scenes or cameras."""
    return _bounce.cache_merge(inputs=inputs, output=output, force=force)


def filter(input, output, box=None, sphere=None, where=None, remove=False):  # noqa: A001 (the CLI's name)
    """Keeps (or with remove=True drops) the records inside `box` (x0, y0, z0, x1, y1, z1), inside
    `sphere` (x, y, z, r) and for which every `where` term holds ("radius < 0.1", "E.y > 2");
    writes them to `output` (.bic) and returns its counts."""
    return _bounce.cache_filter(input=input, output=output, box=box, sphere=sphere, where=where, remove=remove)


def export(input, output):
    """Writes the records of a cache file as a PLY point cloud; returns the counts."""
    return _bounce.cache_export(input=input, output=output)
