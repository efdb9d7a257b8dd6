"""Shared fixtures: the source tree, the built CLI (as an independent front end to compare
with), and the shared real captures (tests skip when absent)."""

import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("RINGTRACK_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
CLI = str(pathlib.Path(os.environ.get(
    "RINGTRACK_CLI", SOURCE_DIR / "build" / "apps" / "ringtrack" / "ringtrack")).resolve())
SHARED_DATA = SOURCE_DIR.parent / "shared" / "data"


def run_cli(*args, check=True):
    return subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, check=check)


@pytest.fixture(scope="session")
def simulated_sequence(tmp_path_factory):
    """A 4 s crowd sequence written by `ringtrack simulate`, run by `ringtrack run`."""
    root = tmp_path_factory.mktemp("seq")
    seq, out = root / "crowd", root / "out"
    run_cli("simulate", "2", "--duration", "4", "--out", seq)
    run_cli("run", seq, "--out", out, "--quiet", "--no-plots")
    return seq, out
