"""Input files (scene files, spectrum CSVs, grids, envmap images) are read only when they are regular files of
at most a stated size: a named pipe (FIFO) would hang the reader, a device such as /dev/zero never ends, and a
huge file would fill the memory before any check could speak."""

import stat
from pathlib import Path

from .checks import byte_size
from .errors import SpectralError

MiB, GiB = 2**20, 2**30
# Far above any real file of each kind: a 1 nm spectrum is about 10 KiB, a scene file without inline grids a
# few MiB; a 2048³ float32 grid is 32 GiB and a 32k × 16k float32 map 6 GiB.
SCENE_LIMIT = 256 * MiB
SPECTRUM_LIMIT = 64 * MiB
GRID_LIMIT = 64 * GiB
IMAGE_LIMIT = 16 * GiB

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def regular_file(path, what: str, limit: int) -> Path:
    """`path` if it names a regular file (through links) of at most `limit` bytes, else a SpectralError that
    names `what` ("spectrum file", ...) and the file and says why."""
    path = Path(path)
    try:
        info = path.stat()
    except FileNotFoundError:
        raise SpectralError(f"{what} {path} does not exist") from None
    except OSError as problem:
        raise SpectralError(f"{what} {path} cannot be read: {problem.strerror or problem}") from None
    if not stat.S_ISREG(info.st_mode):
        kind = next((name for test, name in _KINDS if test(info.st_mode)), "not a file")
        raise SpectralError(f"{what} {path} is {kind}, not a regular file: only files are read")
    if info.st_size > limit:
        raise SpectralError(f"{what} {path} is {byte_size(info.st_size)}, more than the {byte_size(limit)} the "
                            f"tracer reads from a {what}")
    return path
