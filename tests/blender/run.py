"""Runs the add-on's pytest suite inside Blender (CTest's Blender.Addon):
    blender -b --factory-startup --python-exit-code 1 -P tests/blender/run.py -- [pytest args]
The bounce module comes from $PYTHONPATH (the build's python/ folder), the add-on from blender/."""

import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path[:0] = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p] + [os.path.join(ROOT, "blender"), HERE]

import pytest  # noqa: E402 (after the paths)

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
code = pytest.main(["-q", "-p", "no:cacheprovider", *(args or [HERE])])
sys.exit(int(code))
