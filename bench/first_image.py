"""First-image times (issue 31 items 1 and 2): a new process renders a small scene to its first image, as
the CLI does (`python -m addon.tracer render scene.json`, the tracer imported as `addon.tracer`) and as
the add-on does in Blender (the `bpy` module: the extension zip installed in a throw-away Blender user
folder, the tracer imported as `bl_ext.user_default.spectral_volume.addon.tracer`, F12 on a demo .blend).

Each run says whether its kernel was loaded from the cache or compiled. The add-on's run after the CLI's,
on the same cache folder, shows the cache shared across the two import names: it must load what the CLI
compiled (the script stops with an error if it compiles). `--cold` starts from an empty cache folder
(cold = empty cache, new process: minutes); without it the per-user cache is used as it is.

    python -m bench.first_image            # warm: CLI, then add-on, on the per-user cache
    python -m bench.first_image --cold     # CLI cold, CLI warm, add-on warm (reuse); add-on cold
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from addon.tracer.kernels import numba_cache
from addon.tracer.scene_io import save_scene

from bench.measure import machine
from bench.scenes import CloudSpec, cloud_scene

ROOT = Path(__file__).resolve().parent.parent
BLEND = ROOT / "demo_blends" / "rayleigh.blend"
TRACER = "bl_ext.user_default.spectral_volume.addon.tracer"

# Run by the add-on's process: install and enable the zip, open the .blend at a quarter of its resolution
# and 4 samples, F12; print the seconds of each step and how the kernel came (the render's own cache
# statistics, and the background compile's log if one ran).
ADDON_PROBE = f"""
import sys, time
start = time.perf_counter()
import bpy
imported = time.perf_counter()
bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo="user_default", enable_on_install=True)
enabled = time.perf_counter()
bpy.ops.wm.open_mainfile(filepath=sys.argv[2])
scene = bpy.context.scene
scene.render.resolution_percentage, scene.spectral.samples = 25, 4
opened = time.perf_counter()
bpy.ops.render.render()
done = time.perf_counter()
kernel = sys.modules["{TRACER}.kernels.numba_backend"].render_tile
loaded = sum(kernel.stats.cache_hits.values())
cache = sys.modules["{TRACER}.kernels.numba_cache"]
log = cache.kernel_folder() / sys.modules["{TRACER}.background_compile"].LOG_NAME
background = log.read_text().splitlines()[-1] if log.exists() else "none"
print(f"{{imported - start:.1f}} {{enabled - imported:.1f}} {{done - opened:.1f}} {{loaded}} {{background}}")
"""


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cold", action="store_true", help="start from empty cache folders (compiles: minutes)")
    return parser.parse_args(argv)


def extension_zip(folder: Path) -> Path:
    """The linux/windows/macOS zip for this machine, built by tools/build_extension.py into `folder`."""
    platform = {"linux": "linux-x64", "win32": "windows-x64"}.get(sys.platform, "macos-arm64")
    subprocess.run([sys.executable, str(ROOT / "tools" / "build_extension.py"), "--platform", platform,
                    "--out", str(folder)], check=True, capture_output=True)
    (package,) = folder.glob("*.zip")
    return package


def cli_run(cache: Path, work: Path) -> str:
    """One CLI render in a new process: its wall time and the kernel notice it printed."""
    scene = save_scene(cloud_scene(CloudSpec(resolution=32, width=64, height=40), spp=4), work / "scene")
    env = {**os.environ, numba_cache.CACHE_DIR_VARIABLE: str(cache), "PYTHONPATH": str(ROOT)}
    begun = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "addon.tracer", "render", str(scene), "--out", str(work / "o.exr")],
                          cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    seconds = time.perf_counter() - begun
    said = [line for line in done.stderr.splitlines() if line.startswith(numba_cache.NOTICES)]
    how = "compiled" if any(line.startswith(numba_cache.COMPILING) for line in said) else "loaded"
    return f"{seconds:6.1f} s to the image (kernel {how}; said: {' / '.join(said) or 'nothing'})"


def addon_run(cache: Path, package: Path, work: Path) -> tuple[str, bool]:
    """One F12 in a new `bpy` process with the extension installed: the figures, and whether it loaded."""
    user = Path(tempfile.mkdtemp(prefix="blender-user-", dir=work))
    env = {**os.environ, numba_cache.CACHE_DIR_VARIABLE: str(cache), "BLENDER_USER_RESOURCES": str(user)}
    done = subprocess.run([sys.executable, "-c", ADDON_PROBE, str(package), str(BLEND)], env=env,
                          capture_output=True, text=True, check=True)
    imported, enabled, render, loaded, background = done.stdout.strip().splitlines()[-1].split(" ", 4)
    compiled_here = not int(loaded)
    return (f"{float(render):6.1f} s from F12 to the image (import bpy {imported} s, install and enable {enabled} s"
            f" before it; kernel {'compiled' if compiled_here else 'loaded'} in the render, background compile: "
            f"{background})"), not compiled_here and "compiled" not in background


def main(argv=None) -> None:
    args = parse(argv)
    print(machine())
    with tempfile.TemporaryDirectory(prefix="spectral-first-image-") as folder:
        work = Path(folder)
        package = extension_zip(work / "dist")
        cache = work / "cache" if args.cold else numba_cache.user_cache_root()
        if args.cold:
            print(f"CLI, cold:      {cli_run(cache, work)}")
        print(f"CLI, warm:      {cli_run(cache, work)}")
        text, reused = addon_run(cache, package, work)
        print(f"add-on, warm:   {text}")
        if not reused:
            raise SystemExit("error: the add-on compiled the kernel the CLI had cached")
        print("the add-on loaded the kernel the CLI cached (one cache for both import names)")
        if args.cold:
            print(f"add-on, cold:   {addon_run(work / 'cache-addon', package, work)[0]}")


if __name__ == "__main__":
    main()
