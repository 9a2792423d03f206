"""The kernel cache: where it lives, what keys it (not the tracer's import name), that a bad cache means a
recompile and a read-only one is read, and getting the kernel ready while asking for cancellation and
saying what it waits for. A tiny function stands in for the kernel (which takes minutes to compile)."""

import ast
import inspect
import json
import os
import pickle
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import numba
import pytest
from llvmlite import binding
from numba import njit

from addon.tracer.kernels import numba_cache
from addon.tracer.kernels.layout import KernelScene

TRACER = numba_cache.TRACER
EXTENSION_PACKAGE = "bl_ext.user_default.spectral_volume.addon.tracer"  # as Blender imports the extension


def add_one(x):
    return x + 1


def kernel(root, monkeypatch):
    """`add_one` as a freshly declared cached kernel, its cache under `root`."""
    monkeypatch.setenv(numba_cache.CACHE_DIR_VARIABLE, str(root))
    return numba_cache.cached(njit(add_one))


def compiles(dispatcher) -> int:
    return sum(dispatcher.stats.cache_misses.values())


def test_the_cache_folder_is_per_user_and_can_be_overridden(monkeypatch, tmp_path):
    monkeypatch.setenv(numba_cache.CACHE_DIR_VARIABLE, str(tmp_path / "mine"))
    assert numba_cache.user_cache_root() == tmp_path / "mine"
    monkeypatch.delenv(numba_cache.CACHE_DIR_VARIABLE)
    monkeypatch.setattr("sys.platform", "linux")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert numba_cache.user_cache_root() == tmp_path / "xdg" / "spectral_volume"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert numba_cache.user_cache_root() == tmp_path / "home" / ".cache" / "spectral_volume"
    monkeypatch.setattr("sys.platform", "darwin")
    assert numba_cache.user_cache_root() == tmp_path / "home" / "Library" / "Caches" / "spectral_volume"
    monkeypatch.setattr("sys.platform", "win32")
    monkeypatch.setenv("LOCALAPPDATA", str(tmp_path / "local"))
    assert numba_cache.user_cache_root() == tmp_path / "local" / "spectral_volume" / "Cache"


def test_the_sources_key_the_folder_not_the_import_name(monkeypatch, tmp_path):
    here = numba_cache.kernel_folder(tmp_path)
    assert here.parent == tmp_path and here == numba_cache.kernel_folder(tmp_path)
    monkeypatch.setattr(numba_cache, "PACKAGE", EXTENSION_PACKAGE)
    assert numba_cache.kernel_folder(tmp_path) == here  # the extension shares the checkout's kernels
    monkeypatch.setattr(numba_cache, "sources_digest", lambda: "edited")
    assert numba_cache.kernel_folder(tmp_path) != here


def test_what_was_pickled_under_another_import_name_is_read_under_this_one(monkeypatch):
    """Numba pickles the tracer's classes by module name: a cache the extension wrote names
    `bl_ext.<repo>.spectral_volume.addon.tracer...`, one the checkout wrote `addon.tracer...`."""
    written = b"c" + EXTENSION_PACKAGE.encode() + b".kernels.layout\nKernelScene\n."
    with pytest.raises(ModuleNotFoundError):
        pickle.loads(written)
    assert numba_cache._loads(written) is KernelScene
    monkeypatch.setattr(numba_cache, "PACKAGE", EXTENSION_PACKAGE)
    assert numba_cache._here("addon.tracer.kernels.layout") == EXTENSION_PACKAGE + ".kernels.layout"
    assert numba_cache._here("addon.tracer") == EXTENSION_PACKAGE
    assert numba_cache._here("numba.core.types") == "numba.core.types"
    assert numba_cache._here("addon.tracers") == "addon.tracers"


def _keyed() -> set[str]:
    """The files the kernel cache's key hashes, relative to the tracer package."""
    return {path.relative_to(TRACER).as_posix()
            for pattern in numba_cache.KERNEL_SOURCES for path in TRACER.glob(pattern)}


def _imported(module: Path) -> set[str]:
    """`module` and the tracer's modules it imports (relative imports), directly or through others."""
    seen, todo = set(), [module]
    while todo:
        path = todo.pop()
        if path.relative_to(TRACER).as_posix() in seen:
            continue
        seen.add(path.relative_to(TRACER).as_posix())
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                base = path.parents[node.level - 1].joinpath(*(node.module or "").split("."))
                candidates = [base.with_suffix(".py")] + [base / f"{alias.name}.py" for alias in node.names]
                todo += [candidate for candidate in candidates if candidate.is_file()]
    return seen


def test_the_key_hashes_exactly_the_modules_the_kernel_compiles_in():
    """Every module the Numba kernels import, directly or not, may put code or constants into the compiled
    kernel, so its edits must change the key; any other module (the lowering, the light and wavelength
    policies) must not, or editing it recompiles the kernel for every user. `numba_cache` only says where
    the kernel is kept. Numba keys a cached kernel by the class of its KernelScene argument and its fields'
    types, not their names, so KernelScene's module is hashed too."""
    kernels = ("numba_backend.py", "first_hit.py")  # the path tracer and the data passes' first hits
    kernel_imports = set().union(*(_imported(TRACER / "kernels" / kernel) for kernel in kernels))
    assert kernel_imports - {"kernels/numba_cache.py"} == _keyed()
    assert Path(inspect.getsourcefile(KernelScene)).relative_to(TRACER).as_posix() in _keyed()


def test_editing_the_lowering_or_a_policy_keeps_the_compiled_kernel(monkeypatch, tmp_path):
    copy = tmp_path / "tracer"
    shutil.copytree(TRACER, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(numba_cache, "TRACER", copy)
    before = numba_cache.sources_digest()
    for module in ("lowering.py", "lights.py", "wavelength_modes.py", "sampling.py", "scene.py"):
        with (copy / module).open("a") as source:
            source.write("# edited\n")
    assert numba_cache.sources_digest() == before
    with (copy / "kernels" / "layout.py").open("a") as source:
        source.write("# edited\n")
    assert numba_cache.sources_digest() != before


def test_the_cpu_compiled_for_keys_the_folder(monkeypatch, tmp_path):
    """NUMBA_CPU_NAME (tools/cpu_variants.py) compiles for another CPU: its kernels go to another folder."""
    here = numba_cache.kernel_folder(tmp_path)  # the host's CPU, or the one make test-cpus names
    other = "k8" if numba_cache.cache_key()["cpu"] != "k8" else "generic"
    monkeypatch.setattr(numba.config, "CPU_NAME", other)
    monkeypatch.setattr(numba.config, "CPU_FEATURES", "")
    assert numba_cache.cache_key()["cpu"] == other and numba_cache.kernel_folder(tmp_path) != here


def test_a_cached_kernel_is_loaded_by_the_next_process(monkeypatch, tmp_path):
    first = kernel(tmp_path, monkeypatch)
    assert first(1) == 2 and compiles(first) == 1
    again = kernel(tmp_path, monkeypatch)  # as a new process would declare it
    assert again(1) == 2 and compiles(again) == 0 and sum(again.stats.cache_hits.values()) == 1
    assert str(numba_cache.kernel_folder(tmp_path)) == again.stats.cache_path


def test_an_index_naming_a_missing_module_means_a_recompile(monkeypatch, tmp_path):
    kernel(tmp_path, monkeypatch)(1)
    (index,) = numba_cache.kernel_folder(tmp_path).glob("*.nbi")
    index.write_bytes(pickle.dumps(numba.__version__) + b"cno_such_module\nKernelScene\n.")
    with pytest.raises(ModuleNotFoundError):
        pickle.loads(index.read_bytes()[len(pickle.dumps(numba.__version__)):])
    again = kernel(tmp_path, monkeypatch)
    assert again(1) == 2 and compiles(again) == 1


def test_an_unwritable_cache_folder_means_no_cache(monkeypatch, tmp_path):
    blocker = tmp_path / "a file"
    blocker.write_text("not a folder")
    dispatcher = kernel(blocker, monkeypatch)
    assert isinstance(dispatcher._cache, numba.core.caching.NullCache)
    assert dispatcher(1) == 2


@pytest.fixture
def writable_again():
    made = []
    yield made
    for folder in made:
        if os.geteuid() == 0:
            subprocess.run(["chattr", "-i", str(folder)])
        folder.chmod(0o755)


def test_a_read_only_cache_holding_the_kernel_is_read(monkeypatch, tmp_path, writable_again):
    assert kernel(tmp_path, monkeypatch)(1) == 2
    folder = numba_cache.kernel_folder(tmp_path)
    writable_again += [tmp_path, folder]
    for folder_ in (tmp_path, folder):
        folder_.chmod(0o555)
        if os.geteuid() == 0 and (shutil.which("chattr") is None
                                  or subprocess.run(["chattr", "+i", str(folder_)]).returncode):
            pytest.skip("cannot make a folder read-only for root here (no chattr +i)")
    with pytest.raises(OSError):
        (folder / "probe").write_text("")
    again = kernel(tmp_path, monkeypatch)
    assert again(1) == 2 and compiles(again) == 0 and sum(again.stats.cache_hits.values()) == 1
    assert again(2.5) == 3.5 and compiles(again) == 1  # a new signature compiles; not saving it is no error


def waited_for(dispatcher, monkeypatch, name=numba_cache.KERNEL) -> list[str]:
    """The notices `ready` gives while `dispatcher(1)` is made ready, from the first poll on (the helper
    thread lingers a few polls after it, for `ready` to see whether it compiled)."""
    monkeypatch.setattr(numba_cache, "NOTICE_AFTER_SECONDS", 0.0)
    release, notices = threading.Event(), []

    def prepare():
        release.wait()
        dispatcher(1)
        time.sleep(6 * numba_cache.POLL_SECONDS)

    def notice(text):
        notices.append(text)
        release.set()

    assert numba_cache.ready(dispatcher, prepare, notice=notice, kernel=name)
    return notices


def test_ready_says_it_loads_a_cached_kernel(monkeypatch, tmp_path):
    kernel(tmp_path, monkeypatch)(1)
    assert waited_for(kernel(tmp_path, monkeypatch), monkeypatch) == [numba_cache.LOADING_MESSAGE]


def test_ready_says_it_compiles_for_as_long_as_the_last_compile_here_took(monkeypatch, tmp_path):
    dispatcher = kernel(tmp_path, monkeypatch)
    assert numba_cache.compile_seconds() is None  # never compiled on this machine
    assert waited_for(dispatcher, monkeypatch)[-1] == "Compiling the kernel (the first time on this machine)…"
    measured = float((tmp_path / numba_cache.COMPILE_SECONDS_FILE).read_text())
    assert numba_cache.compile_seconds() == measured
    (tmp_path / numba_cache.COMPILE_SECONDS_FILE).write_text("123.4\n")
    assert numba_cache.compiling_message() == "Compiling the kernel (about 123 s on this machine)…"


def test_the_gpu_kernel_has_notices_and_a_compile_time_of_its_own(monkeypatch, tmp_path):
    """The CUDA backend's kernel is named in the notices, and its compile's time is kept apart from the CPU
    kernel's."""
    assert waited_for(kernel(tmp_path, monkeypatch), monkeypatch, "GPU kernel")[-1] == (
        "Compiling the GPU kernel (the first time on this machine)…")
    assert numba_cache.compile_seconds("GPU kernel") is not None and numba_cache.compile_seconds() is None
    assert waited_for(kernel(tmp_path, monkeypatch), monkeypatch, "GPU kernel") == ["Loading the GPU kernel…"]


def test_ready_returns_at_a_cancel_while_the_kernel_compiles(monkeypatch, tmp_path):
    dispatcher = kernel(tmp_path, monkeypatch)
    release = threading.Event()
    asked = []

    def cancel():
        asked.append(1)
        return len(asked) >= 2

    assert not numba_cache.ready(dispatcher, release.wait, cancel=cancel)
    assert len(asked) == 2
    release.set()


def test_ready_raises_what_the_prepare_raised(monkeypatch, tmp_path):
    dispatcher = kernel(tmp_path, monkeypatch)

    def prepare():
        raise ValueError("bad scene")

    with pytest.raises(ValueError, match="bad scene"):
        numba_cache.ready(dispatcher, prepare)


def test_key_folders_unused_for_a_month_are_removed(monkeypatch, tmp_path):
    old, recent, unmarked = tmp_path / "kernels-old", tmp_path / "kernels-recent", tmp_path / "kernels-unmarked"
    for folder in (old, recent, unmarked):
        folder.mkdir()
        (folder / "render_tile.nbi").write_text("")
    for folder in (old, recent):
        (folder / "key.json").write_text("{}")
    month_ago = time.time() - (numba_cache.UNUSED_DAYS + 1) * 86400
    os.utime(old / "key.json", (month_ago, month_ago))
    kernel(tmp_path, monkeypatch)
    assert not old.exists() and recent.exists() and numba_cache.kernel_folder(tmp_path).exists()
    assert unmarked.exists()  # just made by another process, which has not written its key yet


# Compiles `add_one` as the build does the shipped kernel: for Numba's generic CPU, into the cache folder
# given; prints the folder (whose key is then `portable_key()`).
PORTABLE_BUILD = """
from numba import njit
from addon.tracer.kernels import numba_cache
from tests.tracer.kernels.test_numba_cache import add_one
assert numba_cache.cached(njit(add_one))(1) == 2
print(numba_cache.kernel_folder())
"""


@pytest.fixture(scope="module")
def portable_build(tmp_path_factory) -> Path:
    """The folder of `add_one` compiled for the generic CPU, as tools/build_extension.py ships the kernel."""
    root = tmp_path_factory.mktemp("portable")
    env = {**os.environ, "NUMBA_CPU_NAME": "generic", numba_cache.CACHE_DIR_VARIABLE: str(root),
           "PYTHONPATH": str(TRACER.parent.parent), numba_cache.NO_PREBUILT_VARIABLE: "1"}
    env.pop("NUMBA_CPU_FEATURES", None)
    done = subprocess.run([sys.executable, "-c", PORTABLE_BUILD], env=env, capture_output=True, text=True,
                          check=True, cwd=TRACER.parent.parent)
    return Path(done.stdout.split()[-1])


def host_compiles_for_its_own_cpu(monkeypatch) -> None:
    """Under tools/cpu_variants.py's generic run this process compiles for the portable CPU itself, where the
    shipped kernel is rightly not used; the tests of a host with another CPU name the host's own then."""
    if numba.config.CPU_NAME == numba_cache.PORTABLE_CPU["cpu"]:
        monkeypatch.setattr(numba.config, "CPU_NAME", binding.get_host_cpu_name())


def shipped(portable_build, monkeypatch, tmp_path, key=None) -> Path:
    """`portable_build` shipped in a prebuilt folder under `tmp_path` (its key.json replaced by `key`), on a
    host whose own kernel is not the portable one."""
    host_compiles_for_its_own_cpu(monkeypatch)
    monkeypatch.setattr(numba_cache, "PREBUILT", tmp_path / "prebuilt")
    monkeypatch.delenv(numba_cache.NO_PREBUILT_VARIABLE, raising=False)
    folder = numba_cache.kernel_folder(tmp_path / "prebuilt", numba_cache.portable_key())
    shutil.copytree(portable_build, folder)
    if key is not None:
        (folder / "key.json").write_text(json.dumps(key))
    return folder


def test_the_shipped_portable_kernel_renders_when_the_host_has_none(portable_build, monkeypatch, tmp_path):
    assert json.loads((portable_build / "key.json").read_text()) == numba_cache.portable_key()
    folder = shipped(portable_build, monkeypatch, tmp_path)
    assert numba_cache.prebuilt_folder() == folder
    dispatcher = kernel(tmp_path / "user", monkeypatch)
    assert dispatcher(1) == 2 and compiles(dispatcher) == 0 and numba_cache.serves_portable(dispatcher)
    assert not list(numba_cache.kernel_folder(tmp_path / "user").glob("*.nbi"))  # the host's is not cached


def test_the_host_kernel_replaces_the_portable_one_once_it_is_cached(portable_build, monkeypatch, tmp_path):
    shipped(portable_build, monkeypatch, tmp_path)
    dispatcher = kernel(tmp_path / "user", monkeypatch)
    assert dispatcher(1) == 2 and numba_cache.serves_portable(dispatcher)
    numba_cache.ready(dispatcher, lambda: dispatcher(1))
    assert numba_cache.serves_portable(dispatcher)  # nothing else cached yet: it stays
    monkeypatch.setenv(numba_cache.NO_PREBUILT_VARIABLE, "1")  # as the background compile runs
    host = kernel(tmp_path / "user", monkeypatch)
    assert host(1) == 2 and compiles(host) == 1
    assert numba_cache.ready(dispatcher, lambda: dispatcher(1))
    assert not numba_cache.serves_portable(dispatcher) and len(dispatcher._cache.retired) == 1 and dispatcher(1) == 2
    assert compiles(dispatcher) == 0 and sum(dispatcher.stats.cache_hits.values()) == 2  # portable, then host's


def test_a_host_compiling_for_the_portable_cpu_uses_its_own_kernel(portable_build, monkeypatch, tmp_path):
    shipped(portable_build, monkeypatch, tmp_path)
    assert numba_cache.prebuilt_folder() is not None
    monkeypatch.setattr(numba.config, "CPU_NAME", numba_cache.PORTABLE_CPU["cpu"])  # NUMBA_CPU_NAME=generic
    monkeypatch.setattr(numba.config, "CPU_FEATURES", numba_cache.PORTABLE_CPU["cpu_features"])
    assert numba_cache.prebuilt_folder() is None


@pytest.mark.parametrize("foreign", ["sources", "numba", "platform", "cpu"])
def test_a_portable_kernel_built_for_other_sources_versions_or_platform_is_not_used(
        portable_build, monkeypatch, tmp_path, foreign):
    key = {**numba_cache.portable_key(), foreign: "something else"}
    shipped(portable_build, monkeypatch, tmp_path, key)
    assert numba_cache.prebuilt_folder() is None
    dispatcher = kernel(tmp_path / "user", monkeypatch)
    assert dispatcher(1) == 2 and compiles(dispatcher) == 1 and not numba_cache.serves_portable(dispatcher)


def test_a_broken_portable_kernel_means_a_compile(portable_build, monkeypatch, tmp_path):
    folder = shipped(portable_build, monkeypatch, tmp_path)
    for data in folder.glob("*.nbc"):
        data.write_bytes(b"not a kernel")
    dispatcher = kernel(tmp_path / "user", monkeypatch)
    assert dispatcher(1) == 2 and compiles(dispatcher) == 1 and not numba_cache.serves_portable(dispatcher)


def test_the_portable_kernel_can_be_switched_off(portable_build, monkeypatch, tmp_path):
    shipped(portable_build, monkeypatch, tmp_path)
    monkeypatch.setenv(numba_cache.NO_PREBUILT_VARIABLE, "1")
    dispatcher = kernel(tmp_path / "user", monkeypatch)
    assert dispatcher(1) == 2 and compiles(dispatcher) == 1 and not numba_cache.serves_portable(dispatcher)
