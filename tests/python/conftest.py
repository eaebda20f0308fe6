"""Shared fixtures of the Python module's tests: where the checkout and the CLI are, and a
temporary folder per test. Run by `make test` (CTest's Python.Module) with PYTHONPATH at
build/python and BOUNCE_BINARY naming the CLI built beside it."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORNELL = ROOT / "scenes" / "cornell" / "cornell.json"
ROLLING = ROOT / "scenes" / "shots" / "cornell-rolling.json"


@pytest.fixture
def cli():
    """Runs the bounce CLI; returns the CompletedProcess (stdout and stderr as text)."""
    binary = os.environ.get("BOUNCE_BINARY", str(ROOT / "build" / "bounce"))

    def run(*args, check=True):
        done = subprocess.run([binary, *map(str, args)], capture_output=True, text=True)
        if check and done.returncode != 0:
            raise AssertionError(f"bounce {' '.join(map(str, args))} exited {done.returncode}: {done.stderr}")
        return done

    return run
