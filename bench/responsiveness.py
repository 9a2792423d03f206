"""Responsiveness of the render loop (issue 13, item 5) and the kernel's compile time (item 6).

For each image size, the benchmark cloud is rendered with `render.render` (the kernel compiled or loaded
beforehand) and cancelled at several moments: `cancel()` starts answering true at the chosen moment,
and the latency is the time from that moment until `render()` returns (the unit in flight, plus
whatever the loop does after it). Also printed: the time to the first progress report, the longest gap
between two reports (the longest unit) and how long planning the passes takes for huge sample counts.
`--compile` also times a cold compile of the kernel in a fresh process with an empty cache folder,
then the same process again loading it from that cache.

    python -m bench.responsiveness                # 128×80, 640×360, 1920×1080, cancels at 0.3–2.1 s
    python -m bench.responsiveness --compile      # … and a cold compile (minutes)
    python -m bench.responsiveness --quick        # 128×80 and 640×360, two cancels each
"""

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from addon.tracer.kernels import numba_cache
from addon.tracer.render import pass_sizes, render

from bench.measure import machine
from bench.scenes import CloudSpec, cloud_scene

ROOT = Path(__file__).resolve().parent.parent
SIZES = ((128, 80), (640, 360), (1920, 1080))
COMPILE_PROBE = """
import time
start = time.perf_counter()
from addon.tracer.render import render
from bench.scenes import CloudSpec, cloud_scene
scene = cloud_scene(CloudSpec(resolution=32, width=4, height=4), spp=1)
ready = time.perf_counter()
render(scene)
print(f"{ready - start:.2f} {time.perf_counter() - ready:.2f}")
"""


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true", help="two small sizes, two cancels each")
    parser.add_argument("--sizes", nargs="+", help="image sizes WIDTHxHEIGHT (default 128x80 640x360 1920x1080)")
    parser.add_argument("--cancel-at", type=float, nargs="+", help="seconds after the start of the render at "
                        "which cancel() starts answering true (default 0.3 0.75 1.2 1.65 2.1)")
    parser.add_argument("--spp", type=int, default=64, help="samples per pixel asked for (default 64)")
    parser.add_argument("--resolution", type=int, default=64, help="cloud grid resolution (default 64)")
    parser.add_argument("--threads", type=int, help="Numba threads (default: all)")
    parser.add_argument("--compile", action="store_true", help="also time a cold compile of the kernel")
    args = parser.parse_args(argv)
    sizes = args.sizes or (["128x80", "640x360"] if args.quick else [f"{w}x{h}" for w, h in SIZES])
    args.sizes = [tuple(int(n) for n in size.split("x")) for size in sizes]
    args.cancel_at = args.cancel_at or ([0.3, 1.0] if args.quick else [0.3, 0.75, 1.2, 1.65, 2.1])
    return args


def cancelled_render(scene, at: float, threads: int | None) -> dict:
    """Render `scene`, cancelling `at` seconds after the start; the figures of that render."""
    reports = []
    start = time.perf_counter()

    def cancel():
        return time.perf_counter() - start >= at

    result = render(scene, threads=threads, cancel=cancel, progress=lambda film, fraction: reports.append(
        time.perf_counter()))
    end = time.perf_counter()
    gaps = [b - a for a, b in zip([start] + reports, reports)]
    return {"latency": end - start - at if result.cancelled else None, "first": gaps[0] if gaps else None,
            "longest": max(gaps[1:], default=None), "units": len(reports)}


def report_loop(args) -> None:
    print("| image | cancels | latency median / max | first progress | longest unit | units before cancel |")
    print("| --- | --- | --- | --- | --- | --- |")
    for width, height in args.sizes:
        scene = cloud_scene(CloudSpec(resolution=args.resolution, width=width, height=height), spp=args.spp)
        runs = [cancelled_render(scene, at, args.threads) for at in args.cancel_at]
        latencies = [run["latency"] for run in runs if run["latency"] is not None]
        longest = max((run["longest"] for run in runs if run["longest"] is not None), default=float("nan"))
        first = statistics.median(run["first"] for run in runs if run["first"] is not None)
        print(f"| {width}×{height} | {len(latencies)} of {len(runs)} | {statistics.median(latencies):.3f} / "
              f"{max(latencies):.3f} s | {first:.3f} s | {longest:.3f} s | "
              f"{', '.join(str(run['units']) for run in runs)} |")


def report_planning() -> None:
    for spp in (3 * 10**5, 10**8):
        start = time.perf_counter()
        count = len(pass_sizes(spp))
        print(f"pass_sizes({spp:.0e}): {count} passes planned in {time.perf_counter() - start:.3f} s")


def report_compile() -> None:
    """A cold compile and a cache load, each in a fresh process with its own empty cache folder."""
    with tempfile.TemporaryDirectory(prefix="spectral-kernel-cache-") as folder:
        env = {**__import__("os").environ, numba_cache.CACHE_DIR_VARIABLE: folder, "PYTHONPATH": str(ROOT)}
        for label in ("cold compile", "from the cache"):
            done = subprocess.run([sys.executable, "-c", COMPILE_PROBE], cwd=ROOT, env=env, capture_output=True,
                                  text=True, check=True)
            imports, first_render = done.stdout.split()
            print(f"{label}: first render of a 4×4 image {first_render} s (imports and scene {imports} s)")


def main(argv=None) -> None:
    args = parse(argv)
    print(machine())
    render(cloud_scene(CloudSpec(resolution=args.resolution, width=4, height=4), spp=1))  # compile or load
    report_loop(args)
    report_planning()
    if args.compile:
        report_compile()


if __name__ == "__main__":
    main()
