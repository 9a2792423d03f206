"""Keeps Numba's on-disk cache of the kernels honest.

Numba's `cache=True` checks only the cached function's own source file, but the kernels inline shared
math from other modules. This discards the cached kernels whenever one of the sources they are compiled
from changed since they were compiled.
"""

import hashlib
from pathlib import Path

TRACER = Path(__file__).resolve().parent.parent
CACHE = Path(__file__).resolve().parent / "__pycache__"
STAMP = CACHE / "kernel-sources.sha256"
KERNEL_SOURCES = ("kernels/numba_backend.py", "kernels/rng.py", "compile.py", "phase.py", "sampling.py", "planck.py",
                  "shared_math.py", "wavelengths.py")


def sources_digest() -> str:
    digest = hashlib.sha256()
    for source in sorted(path for pattern in KERNEL_SOURCES for path in TRACER.glob(pattern)):
        digest.update(source.relative_to(TRACER).as_posix().encode())
        digest.update(source.read_bytes())
    return digest.hexdigest()


def discard_stale_cache() -> None:
    """Delete cached kernels (*.nbi, *.nbc) compiled from other sources than the current ones."""
    digest = sources_digest()
    try:
        if STAMP.read_text() == digest:
            return
        for cached in list(CACHE.glob("*.nbi")) + list(CACHE.glob("*.nbc")):
            cached.unlink(missing_ok=True)
        STAMP.write_text(digest)
    except FileNotFoundError:
        try:
            CACHE.mkdir(exist_ok=True)
            STAMP.write_text(digest)
        except OSError:
            pass  # read-only install: Numba then cannot cache either
    except OSError:
        pass
