"""Shared fixtures: the real meshes (DELTA_DATA_DIR) and the C++ command-line tool (DELTA_CLI),
both passed by CTest (python/CMakeLists.txt), so that results can be compared with C++'s."""

import csv
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import delta


@pytest.fixture(scope="session")
def meshes():
    """The folder of CGAL's meshes (data/meshes), or skip."""
    folder = pathlib.Path(os.environ.get("DELTA_DATA_DIR", "data")) / "meshes"
    if not (folder / "armadillo.off").is_file():
        pytest.skip(f"no real meshes in {folder} (set DELTA_DATA_DIR)")
    return folder


@pytest.fixture(scope="session")
def cli():
    """Runs the `delta` tool with arguments; returns its stdout (fails on a non-zero exit)."""
    tool = os.environ.get("DELTA_CLI", "")
    if not tool or not os.access(tool, os.X_OK):
        pytest.skip("no delta tool (set DELTA_CLI)")

    def run(*arguments):
        done = subprocess.run([tool, *map(str, arguments)], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return done.stdout

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    """Runs `delta ... --json`; returns the parsed object."""
    return lambda *arguments: json.loads(cli(*arguments, "--json"))


def read_csv(path):
    """A CSV file as a list of dicts of strings."""
    with open(path, newline="") as file:
        return list(csv.DictReader(file))


def write_xyz(points, path):
    """Points in the `x y z` text format, every double written so that it reads back exactly."""
    with open(path, "w") as file:
        for x, y, z in points.tolist():
            file.write(f"{x!r} {y!r} {z!r}\n")


@pytest.fixture(scope="session")
def fandisk(meshes):
    return delta.load(meshes / "fandisk.off")


@pytest.fixture(scope="session")
def rng():
    return np.random.default_rng(20240611)
