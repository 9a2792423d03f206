"""Where Numba keeps the compiled kernels: a per-user cache folder that survives reinstalling the extension.

The folder is `$SPECTRAL_VOLUME_CACHE_DIR` when set, else the platform's per-user cache folder
(`$XDG_CACHE_HOME/spectral_volume` or `~/.cache/spectral_volume` on Linux, `~/Library/Caches/spectral_volume`
on macOS, `%LOCALAPPDATA%\\spectral_volume\\Cache` on Windows). Inside it, kernels live in one sub-folder per
key: the kernel sources (Numba's own check sees only the cached function's file, but the kernels inline
code from several modules), the package the tracer was imported as (a cache written as `addon.tracer`
cannot be read as `bl_ext.<repo>.spectral_volume.addon.tracer`: its index names the package's classes), the
Python, Numba and llvmlite versions and the CPU. A cache that cannot be read means a recompile and one
that cannot be written means none: the cache never fails a render.

`ready` gets the kernel compiled (or loaded) in a helper thread, so that a render can be cancelled
and can tell the user while the kernel compiles.
"""

import hashlib
import json
import os
import sys
import threading
import time
from pathlib import Path

from numba.core.caching import CompileResultCacheImpl, FunctionCache, InTreeCacheLocator, NullCache

APP = "spectral_volume"
CACHE_DIR_VARIABLE = "SPECTRAL_VOLUME_CACHE_DIR"
TRACER = Path(__file__).resolve().parent.parent
PACKAGE = __name__.rpartition(".kernels.")[0]  # "addon.tracer" or "bl_ext.<repo>.spectral_volume.addon.tracer"
KERNEL_SOURCES = ("kernels/numba_backend.py", "kernels/rng.py", "kernels/layout.py", "kernels/fluorescent_reservoir.py",
                  "kernels/geometry.py", "kernels/lookups.py", "kernels/dda.py", "kernels/media.py",
                  "kernels/light_sampling.py", "kernels/envmap.py", "phase.py", "binned.py", "planck.py", "shared_math.py",
                  "wavelengths.py", "kernels/surfaces.py")
COMPILE_SECONDS_FILE = "compile-seconds.txt"
DEFAULT_COMPILE_SECONDS = 170.0  # until measured here: a cold compile took 170 s of CPU on the 2-core VM (bench/README.md)
NOTICE_AFTER_SECONDS = 1.0  # loading a cached kernel takes less; compiling it takes minutes
POLL_SECONDS = 0.05
UNUSED_DAYS = 30  # key folders not used for this long (older sources or versions) are removed


def sources_digest() -> str:
    digest = hashlib.sha256()
    for source in sorted(path for pattern in KERNEL_SOURCES for path in TRACER.glob(pattern)):
        digest.update(source.relative_to(TRACER).as_posix().encode())
        digest.update(source.read_bytes())
    return digest.hexdigest()


def user_cache_root() -> Path:
    """The per-user folder for this extension's caches (the environment variable overrides it)."""
    override = os.environ.get(CACHE_DIR_VARIABLE)
    if override:
        return Path(override).expanduser()
    if sys.platform == "win32":
        return Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local") / APP / "Cache"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / APP
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / APP


def cache_key() -> dict:
    """Everything a compiled kernel depends on besides its argument types (which Numba's index keys)."""
    import llvmlite
    import numba
    from llvmlite import binding

    try:
        features = binding.get_host_cpu_features().flatten()
    except RuntimeError:  # LLVM cannot list them on this platform: the CPU's name has to do
        features = ""
    # The CPU the kernels are compiled for: the host's, unless NUMBA_CPU_NAME / NUMBA_CPU_FEATURES say
    # otherwise (tools/cpu_variants.py compiles for other CPUs).
    cpu = numba.config.CPU_NAME or binding.get_host_cpu_name()
    features = numba.config.CPU_FEATURES if numba.config.CPU_FEATURES is not None else features
    return {"sources": sources_digest(), "package": PACKAGE, "python": sys.implementation.cache_tag,
            "numba": numba.__version__, "llvmlite": llvmlite.__version__, "cpu": cpu, "cpu_features": features}


def kernel_folder(root: Path | None = None, key: dict | None = None) -> Path:
    """The folder of the kernels compiled for `key` (default: the current key)."""
    text = json.dumps(key or cache_key(), sort_keys=True)
    return (root or user_cache_root()) / f"kernels-{hashlib.sha256(text.encode()).hexdigest()[:16]}"


def _usable_folder() -> Path | None:
    """The current key's folder, created and marked as used, or None when it cannot be written."""
    try:
        key = cache_key()
        folder = kernel_folder(key=key)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "key.json").write_text(json.dumps(key, indent=1, sort_keys=True))
        _remove_unused(folder.parent, keep=folder)
        return folder
    except OSError:
        return None


def _remove_unused(root: Path, keep: Path) -> None:
    """Delete key folders whose key.json (or, lacking one, the folder) was last written more than
    UNUSED_DAYS ago."""
    cutoff = time.time() - UNUSED_DAYS * 86400
    for folder in root.glob("kernels-*"):
        stamp = folder / "key.json"
        try:
            if folder != keep and (stamp if stamp.exists() else folder).stat().st_mtime < cutoff:
                for item in folder.iterdir():
                    item.unlink(missing_ok=True)
                folder.rmdir()
        except OSError:
            pass  # in use or not ours to delete: it stays


class _Locator(InTreeCacheLocator):
    """Numba's locator, pointed at the current key's kernel folder."""

    folder: Path | None = None  # set by `cached`

    def __init__(self, py_func, py_file):
        super().__init__(py_func, py_file)
        self._cache_path = str(self.folder)


class _KernelCacheImpl(CompileResultCacheImpl):
    _locator_classes = [_Locator]


class KernelCache(FunctionCache):
    """Numba's function cache in the kernel folder, where any failure to load means a recompile and any
    failure to save means no cache (a cache from another package or version, a corrupt or locked file)."""

    _impl_class = _KernelCacheImpl

    def load_overload(self, sig, target_context):
        try:
            return super().load_overload(sig, target_context)
        except Exception:  # noqa: BLE001 - whatever is wrong with the cache, compiling again is right
            return None

    def save_overload(self, sig, data):
        try:
            super().save_overload(sig, data)
        except Exception:  # noqa: BLE001 - a render must not fail because its kernel could not be cached
            pass


def cached(dispatcher):
    """Give a Numba dispatcher (a kernel declared without `cache=True`) the kernel cache, or no cache
    when the folder cannot be written."""
    _Locator.folder = _usable_folder()
    try:
        dispatcher._cache = KernelCache(dispatcher.py_func) if _Locator.folder is not None else NullCache()
    except (OSError, RuntimeError):  # RuntimeError: Numba found the folder unusable after all
        dispatcher._cache = NullCache()
    return dispatcher


def compile_seconds() -> float:
    """How long the kernel took to compile the last time it compiled on this computer (a default before)."""
    try:
        return float((user_cache_root() / COMPILE_SECONDS_FILE).read_text())
    except (OSError, ValueError):
        return DEFAULT_COMPILE_SECONDS


def record_compile_seconds(seconds: float) -> None:
    try:
        (user_cache_root() / COMPILE_SECONDS_FILE).write_text(f"{seconds:.1f}\n")
    except OSError:
        pass


def compiling_message() -> str:
    """What the user is told while the kernel compiles."""
    return f"Compiling the kernel (first render only, about {compile_seconds():.0f} s)…"


def ready(dispatcher, prepare, cancel=None, notice=None) -> bool:
    """Run `prepare()`, which compiles `dispatcher` or loads it from the cache, in a helper thread while
    asking `cancel()`; if it takes longer than a cache load, tell `notice(compiling_message())`. Returns
    False when cancelled first (the compile goes on in the background and fills the cache)."""
    misses = sum(dispatcher.stats.cache_misses.values())
    failure = []

    def run():
        try:
            prepare()
        except BaseException as error:  # noqa: BLE001 - raised again in the caller's thread
            failure.append(error)

    start = time.perf_counter()
    helper = threading.Thread(target=run, name="spectral-kernel-compile", daemon=True)
    helper.start()
    told = False
    while helper.is_alive():
        helper.join(POLL_SECONDS)
        if cancel is not None and helper.is_alive() and cancel():
            return False
        if notice is not None and not told and time.perf_counter() - start > NOTICE_AFTER_SECONDS:
            notice(compiling_message())
            told = True
    if failure:
        raise failure[0]
    if sum(dispatcher.stats.cache_misses.values()) > misses:
        record_compile_seconds(time.perf_counter() - start)
    return True
