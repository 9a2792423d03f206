"""The Rendered viewport's responsiveness on every demo (issue 17 item 1): from an edit to the first new
image, and how often the image refreshes while it refines.

Each demo's .blend is opened in Blender-as-a-module (`addon.cli.command.open_scene`) and shown in a 512×512 view
through its camera, with `addon.engine.viewport_render.ViewportRenderer` as the engine's `view_update` drives it
(Blender-as-a-module has no window to draw in). Once the full view refines, an edit is made (the seed
changes, so every sample changes) and timed as the viewport's main thread and render thread see it:
- export: the viewport's export of the scene on the main thread (`export_scene(depsgraph, view=...)`);
- stop: from the restart (the export done) until the render in flight returned;
- first image: from the edit until the new render's first (1/8 resolution) image;
- every pixel sampled: from the edit until its first full-resolution image with a sample in every pixel;
then, for up to `--seconds`, the images the draw step would pick up (polled every 5 ms, as view_draw's
redraws would) are counted: refreshes per second, and the samples per second they show.

    python -m bench.viewport                       # every demo, 512×512, 64 viewport samples
    python -m bench.viewport --demos fire --size 256 --samples 16 --seconds 3
"""

import argparse
import dataclasses
import time

import bpy

from addon.cli import command as cli
from addon.jobs import tracer_job
from addon.export.scene import export_scene
from addon.engine.viewport_render import ViewportRenderer
from bench.measure import machine
from demo_blends import build_blends
from demo_blends.run_demos import addon_registered

POLL_SECONDS = 0.005


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--demos", nargs="+", choices=sorted(build_blends.DEMO_SCENES), help="default: all")
    parser.add_argument("--size", type=int, default=512, help="the view's width and height in pixels (512)")
    parser.add_argument("--samples", type=int, default=64, help="Viewport Samples (64)")
    parser.add_argument("--seconds", type=float, default=5.0, help="longest refinement measured per demo (5)")
    return parser.parse_args(argv)


class TimedRun:
    """`tracer_job.render_tracer`, remembering when each render returned."""

    def __init__(self):
        self.returned = []

    def __call__(self, *args, **options):
        result = tracer_job.render_tracer(*args, **options)
        self.returned.append(time.perf_counter())
        return result


def wait_for(condition, timeout: float) -> float | None:
    """Poll `condition()` until true; the time it became true (None on timeout)."""
    deadline = time.perf_counter() + timeout
    while time.perf_counter() < deadline:
        if condition():
            return time.perf_counter()
        time.sleep(POLL_SECONDS)
    return None


def viewport_scene(camera, samples: int):
    """The context's scene exported as the viewport exports it (through `camera`), at `samples`."""
    scene = export_scene(bpy.context.evaluated_depsgraph_get(), view=camera).scene
    return dataclasses.replace(scene, settings=dataclasses.replace(scene.settings, spp=samples))


def measure(demo: str, args) -> dict:
    where = build_blends.DEMO_SCENES[demo]
    cli.open_scene(build_blends.HERE / where.blend, where.scene)
    camera = dataclasses.replace(cli.export_context_scene().scene.camera, width=args.size, height=args.size)
    run = TimedRun()
    viewport = ViewportRenderer(run)
    full = (args.size, args.size)
    viewport.render(viewport_scene(camera, args.samples))
    if wait_for(lambda: viewport.frame is not None and viewport.frame.samples >= 1
                and viewport.frame.resolution == full, 600) is None:
        raise SystemExit(f"{demo}: no full-resolution image within 10 minutes ({viewport.status})")
    time.sleep(0.5)  # the full view refining: a render in flight

    edit = time.perf_counter()
    bpy.context.scene.spectral.seed += 1
    scene = viewport_scene(camera, args.samples)
    exported = time.perf_counter()
    returned_before = len(run.returned)
    request = viewport.render(scene)
    first = wait_for(lambda: viewport.frame.request == request, 60)
    refined = wait_for(lambda: viewport.frame.request == request and viewport.frame.resolution == full
                       and viewport.frame.samples >= 1, 600)
    stop = run.returned[returned_before] if len(run.returned) > returned_before else float("nan")

    frames, last, start_samples = 0, viewport.frame, viewport.frame.samples
    deadline = refined + args.seconds
    while time.perf_counter() < deadline and viewport.busy:
        if viewport.frame is not last:
            frames, last = frames + 1, viewport.frame
        time.sleep(POLL_SECONDS)
    elapsed = time.perf_counter() - refined
    viewport.close()
    return {"export": exported - edit, "stop": stop - exported, "first": first - edit, "full": refined - edit,
            "fps": frames / elapsed, "spp/s": (last.samples - start_samples) / elapsed, "samples": last.samples}


def main(argv=None) -> None:
    args = parse(argv)
    print(machine())
    print(f"{args.size}×{args.size} view, {args.samples} viewport samples, refinement measured for up to "
          f"{args.seconds:g} s")
    print(f"| demo | export | stop | first image (1/8) | every pixel sampled | refreshes/s | samples/s | "
          f"samples after {args.seconds:g} s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    with addon_registered():
        for demo in args.demos or build_blends.DEMO_SCENES:
            m = measure(demo, args)
            print(f"| {demo} | {m['export']:.3f} s | {m['stop']:.3f} s | {m['first']:.3f} s | {m['full']:.2f} s | "
                  f"{m['fps']:.1f} | {m['spp/s']:.1f} | {m['samples']} |", flush=True)


if __name__ == "__main__":
    main()
