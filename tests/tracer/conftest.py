"""Fixtures for tracer tests: tiny valid scene folders (JSON + grids) and the openvdb module.

`scene_data` is a fresh dict of a small valid scene to mutate; `write_scene(data)` writes it as a scene
folder, creating any grid file it references that does not exist yet; `tiny_scene` is that scene loaded.
"""

import json

import numpy as np
import pytest

from addon.tracer import grids, scene_io
from addon.tracer.errors import SpectralError
from addon.tracer.scene import Grid

# A 4×3×2 grid whose every value differs, so any axis swap or flip is visible.
TINY_DENSITY = (np.arange(24, dtype=np.float32).reshape(4, 3, 2) + 1.0) / 24.0
TINY_INDEX_TO_WORLD = [[0.5, 0, 0, -1.0], [0, 0.5, 0, -0.75], [0, 0, 0.5, 0.0], [0, 0, 0, 1]]


def tiny_scene_dict() -> dict:
    return {
        "format": "spectral-volume-scene",
        "version": 1,
        "camera": {
            "to_world": [[1, 0, 0, 0], [0, 0, -1, -5], [0, 1, 0, 0.5], [0, 0, 0, 1]],
            "width": 8,
            "height": 6,
        },
        "media": [
            {
                "name": "cloud",
                "density": {"file": "density.npy", "index_to_world": TINY_INDEX_TO_WORLD},
                "density_scale": 2.0,
                "extinction": 1.0,
                "albedo": 0.9,
            }
        ],
        "lights": [{"kind": "sun", "spectrum": 1.0, "direction": [0, 0, 1]}],
        "render": {"spp": 1},
    }


def _grid_references(data):
    """Every {"file": ...} grid reference in a scene dict (which may be deliberately malformed)."""
    media = data.get("media") if isinstance(data, dict) else None
    for medium in media if isinstance(media, list) else []:
        if not isinstance(medium, dict):
            continue
        emission = medium.get("emission")
        for ref in (medium.get("density"), emission.get("temperature") if isinstance(emission, dict) else None):
            if isinstance(ref, dict) and isinstance(ref.get("file"), str) and ref["file"]:
                yield ref


def _write_missing_grids(data, folder):
    for ref in _grid_references(data):
        path = folder / ref["file"]
        if path.exists():
            continue
        matrix = np.array(ref.get("index_to_world", np.eye(4)), dtype=np.float64)
        grid = Grid(TINY_DENSITY, matrix, ref.get("grid", "density"))
        if path.suffix == ".vdb":
            grids.save_grid_vdb(path, grid)
        else:
            grids.save_grid_npy(path, grid)


@pytest.fixture
def scene_data() -> dict:
    return tiny_scene_dict()


@pytest.fixture
def write_scene(tmp_path):
    """write_scene(data=None, folder=None, make_grids=True) -> path of scene.json.

    `data` defaults to the tiny scene; with `make_grids`, referenced grid files that do not exist are
    written (a 4×3×2 pattern; .vdb files need openvdb)."""

    def write(data=None, folder=None, make_grids=True):
        folder = tmp_path / "scene" if folder is None else folder
        folder.mkdir(parents=True, exist_ok=True)
        data = tiny_scene_dict() if data is None else data
        if make_grids:
            _write_missing_grids(data, folder)
        path = folder / scene_io.SCENE_FILE
        path.write_text(json.dumps(data, indent=2), encoding="utf-8")
        return path

    return write


@pytest.fixture
def tiny_scene(write_scene):
    return scene_io.load_scene(write_scene())


@pytest.fixture
def openvdb():
    """The openvdb module (standalone or Blender's), or skip the test."""
    try:
        return grids.openvdb_module()
    except SpectralError as problem:
        pytest.skip(str(problem))
