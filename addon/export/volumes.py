"""Volume objects → grids: the VDB file of the current frame, or the evaluated grids when modifiers
(or geometry nodes) change them.

A file-backed volume without modifiers is read straight from `grids.frame_filepath` (the file Blender
chose for the frame of a sequence). Otherwise the evaluated grids are written to a temporary VDB file
with `VolumeGrids.save` and read back. Either way the grid's index-to-object transform is composed
with the world matrix of the object or of its instance.
"""

import tempfile
from pathlib import Path

import bpy
import numpy as np

from ..tracer.errors import SpectralError
from ..tracer.grids import load_grid
from ..tracer.scene import Grid


def _world(grid: Grid, matrix_world) -> Grid:
    return Grid(values=grid.values, index_to_world=np.array(matrix_world, dtype=np.float64) @ grid.index_to_world,
                name=grid.name)


def _has_active_modifiers(obj, depsgraph) -> bool:
    render = depsgraph.mode == "RENDER"
    return any(modifier.show_render if render else modifier.show_viewport for modifier in obj.original.modifiers)


def _file_path(obj, depsgraph) -> Path:
    """The VDB file Blender reads for this frame (for a sequence: the frame's file)."""
    volume = obj.data
    frame = depsgraph.scene.frame_current
    if not volume.filepath:
        raise SpectralError(f"Volume {obj.name!r} has no VDB file: choose one in its Object Data properties")
    if volume.grids.frame_filepath:
        path = Path(bpy.path.abspath(volume.grids.frame_filepath, library=volume.library))
    elif volume.is_sequence:
        raise SpectralError(f"Volume {obj.name!r}: its sequence {volume.filepath} has no file for frame {frame} "
                            "(the frame lies outside the sequence, or its files are missing)")
    else:
        path = Path(bpy.path.abspath(volume.filepath, library=volume.library))
    if not path.is_file():
        raise SpectralError(f"Volume {obj.name!r}: VDB file {path} does not exist (frame {frame})")
    return path


def _load(path: Path, names, obj, matrix) -> list[Grid]:
    try:
        return [_world(load_grid(path, name), matrix) for name in names]
    except SpectralError as problem:
        raise SpectralError(f"Volume {obj.name!r}: {problem}") from None


def volume_grids(obj, depsgraph, names, matrix) -> list[Grid]:
    """The grids called `names` of an evaluated Volume object (or Geometry Nodes volume instance) whose
    world matrix is `matrix`, in world space."""
    if not _has_active_modifiers(obj, depsgraph):
        return _load(_file_path(obj, depsgraph), names, obj, matrix)
    with tempfile.TemporaryDirectory(prefix="spectral_volume_") as folder:
        path = Path(folder) / "evaluated.vdb"
        if not obj.data.grids.save(str(path)):
            raise SpectralError(f"Volume {obj.name!r}: its evaluated grids cannot be saved "
                                f"({obj.data.grids.error_message or 'no grids at this frame'})")
        return _load(path, names, obj, matrix)
