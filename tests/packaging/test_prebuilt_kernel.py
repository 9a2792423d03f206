"""The zip ships a portable kernel for this platform (tools/build_extension.py, `add_prebuilt_kernel`), keyed
by the sources it holds, and the installed extension renders with it from an empty kernel cache instead of
compiling (addon/tracer/kernels/numba_cache.py)."""

import json
import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

from addon.tracer.kernels import numba_cache

ROOT = Path(__file__).resolve().parents[2]
PREBUILT = "addon/tracer/kernels/prebuilt/"

# F12 of a small scene in the installed extension, with an empty kernel cache and no background compile:
# prints how the kernel came.
F12_SCRIPT = textwrap.dedent(
    """
    import sys
    import bpy
    bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo="user_default", enable_on_install=True)
    bpy.ops.wm.open_mainfile(filepath=sys.argv[2])
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 32, 20, 100
    scene.spectral.samples = 2
    bpy.ops.render.render()
    tracer = "bl_ext.user_default.spectral_volume.addon.tracer"
    cache, kernel = sys.modules[tracer + ".kernels.numba_cache"], sys.modules[tracer + ".kernels.numba_backend"]
    stats = kernel.render_tile.stats
    print("KERNEL", sum(stats.cache_misses.values()), sum(stats.cache_hits.values()),
          cache.serves_portable(kernel.render_tile), cache.prebuilt_folder())
    """
)


def test_the_zip_holds_the_portable_kernel_of_its_sources(extension_zip):
    names = zipfile.ZipFile(extension_zip).namelist()
    shipped = [name for name in names if name.startswith(PREBUILT)]
    (folder,) = {name[len(PREBUILT):].split("/")[0] for name in shipped}
    assert folder == numba_cache.kernel_folder(Path(), numba_cache.portable_key()).name
    assert {Path(name).suffix for name in shipped} == {".json", ".nbi", ".nbc"}
    key = json.loads(zipfile.ZipFile(extension_zip).read(f"{PREBUILT}{folder}/key.json"))
    assert key == numba_cache.portable_key() and key["cpu"] == "generic"  # this checkout's sources and Numba


def test_the_installed_extension_renders_from_an_empty_cache_without_compiling(extension_zip, tmp_path):
    script = tmp_path / "f12.py"
    script.write_text(F12_SCRIPT)
    env = {**os.environ, "BLENDER_USER_RESOURCES": str(tmp_path / "user"),
           numba_cache.CACHE_DIR_VARIABLE: str(tmp_path / "empty cache"),
           "SPECTRAL_VOLUME_NO_BACKGROUND_COMPILE": "1"}
    env.pop(numba_cache.NO_PREBUILT_VARIABLE, None)
    # Blender as a user starts it: compiling for the host's CPU (under NUMBA_CPU_NAME=generic, as `make test-cpus`
    # or a run as if on another CPU sets it, the portable kernel would be the host's own and not offered as such)
    env.pop("NUMBA_CPU_NAME", None)
    done = subprocess.run([sys.executable, str(script), str(extension_zip), str(ROOT / "demo_blends" / "rayleigh.blend")],
                          env=env, capture_output=True, text=True, timeout=1800)  # a compile, if it failed: minutes
    line = next((line for line in done.stdout.splitlines() if line.startswith("KERNEL ")), None)
    assert line is not None, done.stdout + done.stderr
    misses, hits, portable, folder = line.split(" ", 4)[1:]
    assert (misses, hits, portable) == ("0", "1", "True"), line
    assert "/extensions/user_default/spectral_volume/addon/tracer/kernels/prebuilt/kernels-" in folder
    assert not list((tmp_path / "empty cache").glob("kernels-*/*.nbi"))  # nothing compiled into it
