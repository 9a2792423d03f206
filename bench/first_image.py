"""First-image times (issue 31 items 1 and 2): a new process renders a small scene to its first image, as
the CLI does (`python -m addon.tracer render scene.json`, the tracer imported as `addon.tracer`) and as
the add-on does in Blender (the `bpy` module: the extension zip installed in a throw-away Blender user
folder, the tracer imported as `bl_ext.user_default.spectral_volume.addon.tracer`, F12 on a demo .blend).

Both run the tracer from the zip this script builds (tools/build_extension.py), so both can use the portable
kernel it ships (addon/tracer/kernels/numba_cache.py): the CLI from the zip's `addon/` folder extracted.
Each run says how its kernel came: compiled, loaded from the user cache (the host's kernel), or the
portable one. "Cold" is an empty kernel cache folder and a new process; "compiling" runs switch the
portable kernel off (SPECTRAL_VOLUME_NO_PREBUILT), as before it shipped. The add-on's cold run with the
portable kernel lets the background compile (addon/tracer/background_compile.py) finish, says when the
host's kernel was ready, and the next F12 (a new process, "warm") loads it.

Also: the portable kernel's speed against the host's (pixel samples per second of one larger render,
each in a new process; the host's from the cache the runs before compiled), and where a warm CLI
render's time goes (a probe timing each step in one process).

    python -m bench.first_image            # warm: per-user cache as it is (CLI, breakdown, speed, add-on)
    python -m bench.first_image --cold     # every case from empty caches (three compiles: 15-40 minutes)
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

from addon.tracer.kernels import numba_cache
from addon.tracer.scene_io import save_scene

from bench.measure import machine
from bench.scenes import CloudSpec, cloud_scene

ROOT = Path(__file__).resolve().parent.parent
BLEND = ROOT / "demo_blends" / "rayleigh.blend"
TRACER = "bl_ext.user_default.spectral_volume.addon.tracer"
SMALL = CloudSpec(resolution=32, width=64, height=40)  # the first image
LARGE = CloudSpec(resolution=64, width=160, height=100)  # the speed comparison, at SPEED_SPP
SPEED_SPP = 32

# Run by the add-on's process: install and enable the zip, open the .blend at a quarter of its resolution
# and 4 samples, F12; print the seconds of each step and how the kernel came (the render's own cache
# statistics, and the background compile's log if one ran, after waiting for it: the seconds from F12 to
# the host's kernel in the cache).
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
cache = sys.modules["{TRACER}.kernels.numba_cache"]
background = sys.modules["{TRACER}.background_compile"]
how = "portable" if cache.serves_portable(kernel) else "loaded" if sum(kernel.stats.cache_hits.values()) else "compiled"
if background.running():
    background._process.wait()
host_ready = time.perf_counter() - opened if background.started() else 0.0
log = cache.kernel_folder() / background.LOG_NAME
said = log.read_text().splitlines()[-1] if log.exists() else "none"
print(f"{{imported - start:.1f}} {{enabled - imported:.1f}} {{done - opened:.1f}} {{how}} {{host_ready:.1f}} {{said}}")
"""

# Run by a CLI-like process on a warm cache: the seconds of each step to the first image.
BREAKDOWN_PROBE = """
import sys, time
start = time.perf_counter()
import numba
numba_imported = time.perf_counter()
from addon.tracer import backends, render, scene_io
tracer_imported = time.perf_counter()
scene = scene_io.load_scene(sys.argv[1])
kernel_scene = render.band_scenes(scene)[0]
loaded = time.perf_counter()
backends.named("numba").prepare(kernel_scene, scene.settings.seed, None, None)
ready = time.perf_counter()
render.render(scene)
rendered = time.perf_counter()
print(f"import numba {numba_imported - start:.2f} s, import the tracer {tracer_imported - numba_imported:.2f} s, "
      f"read and lower the scene {loaded - tracer_imported:.2f} s, load the kernel {ready - loaded:.2f} s, "
      f"render {rendered - ready:.2f} s")
"""


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cold", action="store_true", help="start from empty cache folders (compiles: minutes)")
    return parser.parse_args(argv)


def extension_zip(folder: Path) -> Path:
    """The zip for this machine, built by tools/build_extension.py into `folder` (with the portable kernel,
    compiled into the per-user cache the first time for these sources: minutes)."""
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        from build_extension import host_platform
    finally:
        sys.path.remove(str(ROOT / "tools"))
    begun = time.perf_counter()
    subprocess.run([sys.executable, str(ROOT / "tools" / "build_extension.py"), "--platform", host_platform(),
                    "--out", str(folder)], check=True, capture_output=True)
    (package,) = folder.glob("*.zip")
    print(f"built {package.name} in {time.perf_counter() - begun:.0f} s", flush=True)
    return package


def extracted(package: Path, folder: Path) -> Path:
    """The zip's `addon/` package (the tracer with its portable kernel) under `folder`, for the CLI."""
    with zipfile.ZipFile(package) as archive:
        archive.extractall(folder, [name for name in archive.namelist() if name.startswith("addon/")])
    return folder


def environment(cache: Path, portable: bool, **more) -> dict:
    env = {**os.environ, numba_cache.CACHE_DIR_VARIABLE: str(cache), **more}
    env.pop(numba_cache.NO_PREBUILT_VARIABLE, None)
    return env if portable else {**env, numba_cache.NO_PREBUILT_VARIABLE: "1"}


def cli_run(tree: Path, cache: Path, work: Path, portable: bool) -> str:
    """One CLI render of the small scene in a new process: its wall time and how the kernel came."""
    scene = save_scene(cloud_scene(SMALL, spp=4), work / "small")
    host_cached = any(cache.glob("kernels-*/*.nbi"))
    begun = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "addon.tracer", "render", str(scene), "--out", str(work / "o.exr")],
                          cwd=tree, env=environment(cache, portable, PYTHONPATH=str(tree)), capture_output=True,
                          text=True, check=True)
    seconds = time.perf_counter() - begun
    said = [line for line in done.stderr.splitlines() if line.startswith(numba_cache.NOTICES)]
    compiled = any(line.startswith(numba_cache.COMPILING) for line in said)
    how = "compiled" if compiled else "portable" if portable and not host_cached else "loaded from the cache"
    return f"{seconds:6.1f} s to the image (kernel {how}; said: {' / '.join(said) or 'nothing'})"


def breakdown(tree: Path, cache: Path, work: Path) -> str:
    scene = save_scene(cloud_scene(SMALL, spp=4), work / "small")
    done = subprocess.run([sys.executable, "-c", BREAKDOWN_PROBE, str(scene)], cwd=tree,
                          env=environment(cache, False, PYTHONPATH=str(tree)), capture_output=True, text=True,
                          check=True)
    return done.stdout.strip()


def speed(tree: Path, cache: Path, work: Path, portable: bool) -> float:
    """Pixel samples per second of the large scene (SPEED_SPP samples), rendered by a new process."""
    scene = save_scene(cloud_scene(LARGE, spp=SPEED_SPP), work / "large")
    stats = work / "stats.json"
    subprocess.run([sys.executable, "-m", "addon.tracer", "render", str(scene), "--out", str(work / "o.exr"),
                    "--stats", str(stats), "--quiet"], cwd=tree,
                   env=environment(cache, portable, PYTHONPATH=str(tree)), capture_output=True, check=True)
    return json.loads(stats.read_text())["pixel_samples_per_second"]


def addon_run(cache: Path, package: Path, work: Path, portable: bool) -> tuple[str, str]:
    """One F12 in a new `bpy` process with the extension installed: the figures, and how the kernel came."""
    user = Path(tempfile.mkdtemp(prefix="blender-user-", dir=work))
    done = subprocess.run([sys.executable, "-c", ADDON_PROBE, str(package), str(BLEND)],
                          env=environment(cache, portable, BLENDER_USER_RESOURCES=str(user)),
                          capture_output=True, text=True, check=True)
    imported, enabled, render, how, host_ready, background = done.stdout.strip().splitlines()[-1].split(" ", 5)
    ready = f", the host's kernel in the cache {host_ready} s after F12" if float(host_ready) else ""
    return (f"{float(render):6.1f} s from F12 to the image (import bpy {imported} s, install and enable {enabled} s"
            f" before it; kernel: {how}; background compile: {background}{ready})"), how


def main(argv=None) -> None:
    args = parse(argv)
    print(machine(), flush=True)
    with tempfile.TemporaryDirectory(prefix="spectral-first-image-") as folder:
        work = Path(folder)
        package = extension_zip(work / "dist")
        tree = extracted(package, work / "extension")
        host = work / "cache" if args.cold else numba_cache.user_cache_root()
        if args.cold:  # the host's kernel comes from the add-on's background compile, then serves the CLI
            print(f"CLI, cold, portable kernel:   {cli_run(tree, work / 'cache-cli', work, portable=True)}", flush=True)
            print(f"add-on, cold, portable:       {addon_run(host, package, work, portable=True)[0]}", flush=True)
            print(f"add-on, warm (next F12):      {addon_run(host, package, work, portable=True)[0]}", flush=True)
        print(f"CLI, warm:                    {cli_run(tree, host, work, portable=False)}", flush=True)
        print(f"CLI, warm, where it goes:     {breakdown(tree, host, work)}", flush=True)
        host_speed = speed(tree, host, work, portable=False)
        portable_speed = speed(tree, work / "cache-speed", work, portable=True)
        print(f"speed ({LARGE.width}×{LARGE.height}, {SPEED_SPP} spp): host kernel {host_speed:,.0f}, portable kernel "
              f"{portable_speed:,.0f} pixel samples/s ({portable_speed / host_speed:.2f}×)", flush=True)
        if args.cold:  # as before the portable kernel shipped
            print(f"CLI, cold, compiling:         {cli_run(tree, work / 'cache-compiling', work, portable=False)}",
                  flush=True)
            compiling = work / "cache-addon-compiling"
            print(f"add-on, cold, compiling:      {addon_run(compiling, package, work, portable=False)[0]}", flush=True)
        else:
            text, how = addon_run(host, package, work, portable=True)
            print(f"add-on, warm:                 {text}")
            if how != "loaded":
                raise SystemExit("error: the add-on did not load the kernel the CLI cached")
            print("the add-on loaded the kernel the CLI cached (one cache for both import names)")


if __name__ == "__main__":
    main()
