"""Where Numba keeps the compiled kernels: a per-user cache folder that survives reinstalling the extension.

The folder is `$SPECTRAL_VOLUME_CACHE_DIR` when set, else the platform's per-user cache folder
(`$XDG_CACHE_HOME/spectral_volume` or `~/.cache/spectral_volume` on Linux, `~/Library/Caches/spectral_volume`
on macOS, `%LOCALAPPDATA%\\spectral_volume\\Cache` on Windows). Inside it, kernels live in one sub-folder per
key: the content of the kernel sources (Numba's own check sees only the cached function's file, but the
kernels inline code from several modules), the Python, Numba and llvmlite versions and the CPU; not the
name the tracer was imported as. The checkout (`addon.tracer`), the CLI and the installed extension
(`bl_ext.<repo>.spectral_volume.addon.tracer`) share one kernel: what Numba pickled under one name (the
classes and modules of the tracer) is read under the current one (`_Unpickler`). A folder that cannot be
written is still read; a cache that cannot be read means a recompile and one that cannot be written means
none: the cache never fails a render.

The extension's zip also ships a portable kernel (compiled by `make extension` for Numba's "generic" CPU of
the build's platform, in PREBUILT under the folder of its own key: `portable_key`). When the host's kernel
is not cached, that one is loaded (read-only) and renders at once; `background_compile` meanwhile compiles
the host's kernel, which replaces it at the next render (`ready`). It is used only when its key.json is
the key the running sources, versions and platform give (`prebuilt_folder`); anything wrong with it
means a compile, as with the user cache.

`ready` gets the kernel compiled (or loaded) in a helper thread, so that a render can be cancelled
and can tell the user which of the two it waits for: loading takes seconds, compiling minutes, about as
long as the last compile on this machine (`COMPILE_SECONDS_FILE`).
"""

import hashlib
import io
import json
import os
import pickle
import re
import sys
import threading
import time
from pathlib import Path

from numba.core import environment
from numba.core.caching import (CompileResultCacheImpl, FunctionCache, InTreeCacheLocator, IndexDataCacheFile,
                                NullCache)

APP = "spectral_volume"
CACHE_DIR_VARIABLE = "SPECTRAL_VOLUME_CACHE_DIR"
TRACER = Path(__file__).resolve().parent.parent
PACKAGE = __name__.rpartition(".kernels.")[0]  # "addon.tracer" or "bl_ext.<repo>.spectral_volume.addon.tracer"
TRACER_MODULE = re.compile(r"^(?:[\w.]+\.)?addon\.tracer(?=\.|$)")  # the tracer's modules, under any import name
KERNEL_SOURCES = ("kernels/numba_backend.py", "kernels/rng.py", "kernels/layout.py", "kernels/fluorescent_reservoir.py",
                  "kernels/geometry.py", "kernels/lookups.py", "kernels/dda.py", "kernels/media.py",
                  "kernels/light_sampling.py", "kernels/envmap.py", "phase.py", "binned.py", "planck.py", "shared_math.py",
                  "wavelengths.py", "kernels/surfaces.py", "constants.py", "kernels/transparency.py",
                  "kernels/light_split.py", "kernels/first_hit.py", "kernels/spectrum_bins.py", "kernels/estimator.py")
PREBUILT = TRACER / "kernels" / "prebuilt"  # the portable kernel the extension's zip ships (none in a checkout)
NO_PREBUILT_VARIABLE = "SPECTRAL_VOLUME_NO_PREBUILT"  # set (to anything) to never load it
PORTABLE_CPU = {"cpu": "generic", "cpu_features": ""}  # what Numba compiles for under NUMBA_CPU_NAME=generic
COMPILE_SECONDS_FILE = "compile-seconds.txt"  # in the cache root: how long the last compile on this machine took
KERNEL = "kernel"  # what the notices call the CPU kernel (`ready`'s `kernel` names another, e.g. a GPU kernel)
LOADING_MESSAGE = f"Loading the {KERNEL}…"
COMPILING = f"Compiling the {KERNEL}"
NOTICES = (LOADING_MESSAGE, COMPILING)  # how every notice of `ready` begins
NOTICE_AFTER_SECONDS = 1.0  # loading a cached kernel usually takes less; compiling it takes minutes
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
    return {"sources": sources_digest(), "python": sys.implementation.cache_tag, "numba": numba.__version__,
            "llvmlite": llvmlite.__version__, "platform": binding.get_process_triple(), "cpu": cpu,
            "cpu_features": features}


def portable_key() -> dict:
    """The key of the portable kernel these sources and versions would ship for this platform."""
    return {**cache_key(), **PORTABLE_CPU}


def prebuilt_folder() -> Path | None:
    """The shipped portable kernel's folder if it was built from these very sources, versions and platform
    (its key.json says so) and the host's own kernel is another (not NUMBA_CPU_NAME=generic already);
    None otherwise, or when NO_PREBUILT_VARIABLE is set."""
    if os.environ.get(NO_PREBUILT_VARIABLE):
        return None
    try:
        key = portable_key()
        folder = kernel_folder(PREBUILT, key)
        shipped = json.loads((folder / "key.json").read_text())
    except (OSError, ValueError):  # none shipped, or unreadable
        return None
    return folder if shipped == key and key != cache_key() else None


def kernel_folder(root: Path | None = None, key: dict | None = None) -> Path:
    """The folder of the kernels compiled for `key` (default: the current key)."""
    text = json.dumps(key or cache_key(), sort_keys=True)
    return (root or user_cache_root()) / f"kernels-{hashlib.sha256(text.encode()).hexdigest()[:16]}"


def usable_folder(extra_key: dict | None = None) -> Path | None:
    """The current key's folder (with `extra_key`'s items added to the key), created and marked as used where it
    can be written; None when it neither exists nor can be made."""
    try:
        key = {**cache_key(), **(extra_key or {})}
        folder = kernel_folder(key=key)
    except OSError:  # the sources cannot be read to key it
        return None
    try:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "key.json").write_text(json.dumps(key, indent=1, sort_keys=True))
        _remove_unused(folder.parent, keep=folder)
    except OSError:
        return folder if folder.is_dir() else None  # read-only: its kernels are loaded, new ones not saved
    return folder


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
    """Numba's locator, pointed at the current key's kernel folder, which need not be writable."""

    folder: Path | None = None  # set by `cached`

    def __init__(self, py_func, py_file):
        super().__init__(py_func, py_file)
        self._cache_path = str(self.folder)

    def ensure_cache_path(self):
        os.makedirs(self._cache_path, exist_ok=True)  # Numba's also demands a writable folder


def _here(module: str) -> str:
    """`module` with the tracer's package, under whatever name it was pickled, renamed to this one's."""
    return TRACER_MODULE.sub(PACKAGE, module, count=1)


def _rebuild_environment(module, consts, name):
    """Numba's `_rebuild_env`, which imports the module of a kernel's environment by its pickled name."""
    return environment._rebuild_env(_here(module), consts, name)


class _Unpickler(pickle.Unpickler):
    """Reads a kernel cache pickled under another import name of the tracer."""

    def find_class(self, module, name):
        if (module, name) == ("numba.core.environment", "_rebuild_env"):
            return _rebuild_environment
        return super().find_class(_here(module), name)


def _loads(data: bytes):
    return _Unpickler(io.BytesIO(data)).load()


class _KernelCacheFile(IndexDataCacheFile):
    """Numba's index and data files, read with `_Unpickler` (Numba's own reading, but for the unpickler)."""

    def _load_index(self):
        try:
            with open(self._index_path, "rb") as f:
                version = pickle.load(f)
                data = f.read()
        except FileNotFoundError:
            return {}
        if version != self._version:
            return {}
        stamp, overloads = _loads(data)
        return overloads if stamp == self._source_stamp else {}

    def _load_data(self, name):
        with open(self._data_path(name), "rb") as f:
            return _loads(f.read())


class _PortableLocator(_Locator):
    """The locator of the shipped portable kernel's folder."""

    folder: Path | None = None  # set by `cached`


class _KernelCacheImpl(CompileResultCacheImpl):
    _locator_classes = [_Locator]

    def rebuild(self, target_context, payload):
        payload[1].modname = _here(payload[1].modname)  # the function descriptor's module, looked up by name
        return super().rebuild(target_context, payload)


class _PortableCacheImpl(_KernelCacheImpl):
    _locator_classes = [_PortableLocator]


class KernelCache(FunctionCache):
    """Numba's function cache in the kernel folder, where any failure to load means a recompile and any
    failure to save means no cache (a cache from another version, a corrupt, locked or read-only file).
    A kernel the folder lacks is loaded from `portable` (a `_PortableCache`) when given, and those
    signatures are kept in `portable_signatures`."""

    _impl_class = _KernelCacheImpl

    def __init__(self, py_func, portable=None):
        super().__init__(py_func)
        self._cache_file = _KernelCacheFile(self._cache_path, self._impl.filename_base,
                                            self._impl.locator.get_source_stamp())
        self.portable = portable
        self.portable_signatures = []
        self.retired = []  # the portable kernels the host's replaced

    def load_overload(self, sig, target_context):
        try:
            loaded = super().load_overload(sig, target_context)
        except Exception:  # noqa: BLE001 - whatever is wrong with the cache, compiling again is right
            loaded = None
        if loaded is None and self.portable is not None:
            loaded = self.portable.load_overload(sig, target_context)
            if loaded is not None:
                self.portable_signatures.append(sig)
        return loaded

    def holds(self, sig, codegen) -> bool:
        """Whether the folder has a kernel for `sig` (compiled since the portable one was loaded)."""
        try:
            return self._index_key(sig, codegen) in self._cache_file._load_index()
        except Exception:  # noqa: BLE001 - an unreadable index holds nothing
            return False

    def save_overload(self, sig, data):
        try:
            super().save_overload(sig, data)
        except Exception:  # noqa: BLE001 - a render must not fail because its kernel could not be cached
            pass


class _PortableCache(KernelCache):
    """The shipped portable kernel, read-only: indexed under the generic CPU Numba compiled it for."""

    _impl_class = _PortableCacheImpl

    def _index_key(self, sig, codegen):
        signature, (triple, _cpu, _features), hashes = super()._index_key(sig, codegen)
        return signature, (triple, PORTABLE_CPU["cpu"], PORTABLE_CPU["cpu_features"]), hashes

    def save_overload(self, sig, data):
        pass  # shipped as built


def cached(dispatcher):
    """Give a Numba dispatcher (a kernel declared without `cache=True`) the kernel cache, or no cache
    when the folder cannot be written; with the shipped portable kernel behind it when there is one."""
    _Locator.folder = usable_folder()
    _PortableLocator.folder = prebuilt_folder()
    try:
        portable = _PortableCache(dispatcher.py_func) if _PortableLocator.folder is not None else None
    except (OSError, RuntimeError):
        portable = None
    try:
        dispatcher._cache = KernelCache(dispatcher.py_func, portable) if _Locator.folder is not None else NullCache()
    except (OSError, RuntimeError):  # RuntimeError: Numba found the folder unusable after all
        dispatcher._cache = NullCache()
    return dispatcher


def serves_portable(dispatcher) -> bool:
    """Whether `dispatcher` renders with the shipped portable kernel (loaded because the host's was not
    cached)."""
    return bool(getattr(dispatcher._cache, "portable_signatures", ()))


def _prefer_host(dispatcher) -> None:
    """Drop the portable kernel once the host's own is cached for every signature it served, so that the
    next compile loads the host's."""
    cache = dispatcher._cache
    codegen = dispatcher.targetctx.codegen()
    if serves_portable(dispatcher) and all(cache.holds(sig, codegen) for sig in cache.portable_signatures):
        cache.retired += dispatcher.overloads.values()  # kept alive: another thread may be running it
        dispatcher._reset_overloads()  # Numba's own step before recompiling
        cache.portable_signatures.clear()


def _seconds_file(kernel: str) -> Path:
    name = COMPILE_SECONDS_FILE if kernel == KERNEL else f"compile-seconds-{kernel.replace(' ', '-')}.txt"
    return user_cache_root() / name


def compile_seconds(kernel: str = KERNEL) -> float | None:
    """How long the kernel took to compile the last time it compiled on this computer (None before)."""
    try:
        return float(_seconds_file(kernel).read_text())
    except (OSError, ValueError):
        return None


def record_compile_seconds(seconds: float, kernel: str = KERNEL) -> None:
    try:
        _seconds_file(kernel).write_text(f"{seconds:.1f}\n")
    except OSError:
        pass


def compiling_message(kernel: str = KERNEL) -> str:
    """What the user is told while the kernel compiles: as long as the last compile here took, if timed."""
    seconds = compile_seconds(kernel)
    if seconds is None:
        return f"Compiling the {kernel} (the first time on this machine)…"
    return f"Compiling the {kernel} (about {seconds:.0f} s on this machine)…"


def ready(dispatcher, prepare, cancel=None, notice=None, kernel: str = KERNEL) -> bool:
    """Run `prepare()`, which compiles `dispatcher` or loads it from the cache, in a helper thread while
    asking `cancel()`; if it takes longer than NOTICE_AFTER_SECONDS, tell `notice` whether it loads
    ("Loading the `kernel`…") or compiles (`compiling_message(kernel)`; Numba and numba-cuda count a cache miss
    before they compile), again when that changes. Returns False when cancelled first (the compile goes on in the
    background and fills the cache). A portable kernel in use is replaced by the host's once that is cached."""
    _prefer_host(dispatcher)
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
    told = None
    while helper.is_alive():
        helper.join(POLL_SECONDS)
        if cancel is not None and helper.is_alive() and cancel():
            return False
        if notice is not None and helper.is_alive() and time.perf_counter() - start > NOTICE_AFTER_SECONDS:
            compiling = sum(dispatcher.stats.cache_misses.values()) > misses
            if told != compiling:
                notice(compiling_message(kernel) if compiling else f"Loading the {kernel}…")
                told = compiling
    if failure:
        raise failure[0]
    if sum(dispatcher.stats.cache_misses.values()) > misses:
        record_compile_seconds(time.perf_counter() - start, kernel)
    return True
