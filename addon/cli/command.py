"""Headless rendering of a .blend file to multilayer EXRs (and PNGs), one frame or many, as `blender -b -f/-a`.

    python -m addon.cli render FILE.blend --out OUT.exr [--scene NAME] [--frame N | --frames 1-250,300]
        [--resolution WxH] [--percentage N] [--png OUT.png] [--spectral-exr OUT.exr] [--spp N]
        [--scheduler ADDRESS] [--quiet]
    blender -c spectral_render FILE.blend --out OUT.exr [...]   (the same, with the extension installed)

Each frame is exported as F12 renders it and rendered by the render job its Render settings choose (the
tracer or the Cycles emulation, addon/jobs/); its film goes to files through addon/output.py.
Output paths take `#` frame-number placeholders (`out/frame_####.exr`), needed when rendering several
frames. Every option is checked before the file is opened; each frame's files are written together
(`image_io.write_all`) when that frame is done, so a failure at a later frame keeps the earlier ones.

Blender command ids must be Python identifiers, hence `spectral_render`. Exit codes as the tracer's
command line (`addon.tracer.cli`): 0 success, 1 bad input (message on stderr, nothing written),
2 usage error, 70 internal error (a bug, with its traceback), 130 interrupted.
"""

import argparse
import sys
from pathlib import Path

from .frame_options import check_frame_paths, frame_path, parse_frames, parse_resolution
from ..tracer import checks, image_io
from ..tracer.cli import EXIT_OK, ProgressBar, run_reporting, say
from ..tracer.errors import SpectralError
from ..tracer.scene import SPP_MAX

COMMAND = "spectral_render"
CLASSES = ()
_handle = None


def _parser(prog: str) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=prog, description="Render a .blend file with the spectral volume tracer "
                                     "(or its Cycles emulation, when the scene's Render settings choose it)")
    parser.add_argument("blend", type=Path, help=".blend file to render")
    parser.add_argument("--out", type=Path, required=True, help="multilayer EXR to write (Combined, XYZ, "
                        "XYZ Variance passes, named as F12's); '#'s are replaced by the frame number")
    parser.add_argument("--png", type=Path, help="also write a PNG (Standard view at the scene's exposure); "
                        "'#'s are replaced by the frame number")
    parser.add_argument("--spectral-exr", type=Path, metavar="PATH",
                        help="also write the spectral image (one channel per wavelength bin, the OpenEXR spectral "
                             "layout of Fichet et al. 2021; bins: the scene's Spectral EXR settings); '#'s are "
                             "replaced by the frame number")
    parser.add_argument("--scene", help="scene of the file to render (default: the file's active scene)")
    frames = parser.add_mutually_exclusive_group()
    frames.add_argument("--frame", type=int, help="frame to render (default: the file's current frame)")
    frames.add_argument("--frames", metavar="LIST", help="frames to render, e.g. 1-250 or 1,3,5-7 (each once, "
                        "in that order); the output paths need a '#'")
    parser.add_argument("--resolution", metavar="WxH", help="image size in pixels (default: the scene's)")
    parser.add_argument("--percentage", type=int, help="resolution scale in percent (default: the scene's)")
    parser.add_argument("--spp", type=int, help="samples per pixel (default: the scene's)")
    parser.add_argument("--device", choices=("CPU", "GPU"), help="Render ▸ Device to render on, as Cycles' "
                        "--cycles-device (default: the scene's): GPU renders with the CUDA backend")
    parser.add_argument("--scheduler", help="Dask scheduler tcp://HOST:PORT to render on (default: the scene's "
                                            "Render setting; empty: this computer)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    return parser


def open_scene(blend: Path, scene_name: str | None = None):
    """Open `blend` and make its scene `scene_name` (default: the file's active scene) the context's
    scene; returns it. Raises SpectralError when the file or the scene does not exist."""
    import bpy

    if not blend.is_file():
        raise SpectralError(f"blend file {blend} does not exist")
    try:
        bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    except RuntimeError as problem:  # not a blend file, truncated, from a newer Blender...
        reason = str(problem).strip().removeprefix("Error: ")
        raise SpectralError(f"blend file {blend} cannot be opened: {reason}") from None
    if scene_name is not None:
        scene = bpy.data.scenes.get(scene_name)
        if scene is None:
            names = ", ".join(repr(scene.name) for scene in bpy.data.scenes)
            raise SpectralError(f"blend file {blend} has no scene {scene_name!r}; its scenes: {names}")
        bpy.context.window.scene = scene
    return bpy.context.scene


def export_context_scene(frame: int | None = None):
    """Export the context's scene (at `frame`, default its current frame) to a tracer scene, as F12 renders it."""
    import bpy

    from ..export.rendered import export_rendered

    if frame is not None:
        check_frame(frame)
        bpy.context.scene.frame_set(frame)
    return export_rendered(bpy.context.scene, bpy.context.view_layer)


def check_frame(frame: int) -> int:
    """`frame`, or a SpectralError when it lies outside the frames Blender has (it would clamp it)."""
    low, high = _limits("Scene", "frame_current")
    if not low <= frame <= high:
        raise SpectralError(f"--frame: Blender's frames run from {low} to {high}, found {frame}")
    return frame


def _limits(owner: str, name: str) -> tuple[int, int]:
    """The range Blender allows for the setting `name` of `owner` (a bpy.types name)."""
    import bpy

    setting = getattr(bpy.types, owner).bl_rna.properties[name]
    return setting.hard_min, setting.hard_max


def _check_options(args) -> list[int] | None:
    """Every option's value and the first frame's destinations, before the file is opened; returns the
    frames asked for (None: the file's current frame)."""
    if args.spp is not None:
        checks.whole_within(args.spp, "--spp", 1, SPP_MAX)
    frames = None if args.frame is None else [check_frame(args.frame)]
    if args.frames is not None:
        frames = parse_frames(args.frames, _limits("Scene", "frame_current"))
    if args.resolution is not None:
        parse_resolution(args.resolution, _limits("RenderSettings", "resolution_x"))
    low, high = _limits("RenderSettings", "resolution_percentage")
    if args.percentage is not None and not low <= args.percentage <= high:
        raise SpectralError(f"--percentage: must be from {low} to {high}, as in Blender, found {args.percentage}")
    outputs = {"--out": args.out, "--png": args.png, "--spectral-exr": args.spectral_exr}
    check_frame_paths(outputs, frames or [])
    first = 0 if frames is None else frames[0]
    for (option, path), suffix in zip(outputs.items(), (".exr", ".png", ".exr")):
        if path is not None:
            image_io.check_destination(frame_path(path, first), suffix)
    image_io.check_distinct((option, None if path is None else frame_path(path, first))
                            for option, path in outputs.items())
    return frames


def render_blend(args, written: list):
    """Open, then export, render and write each frame, adding the paths written to `written`; yields a
    one-line summary per frame written. Raises SpectralError on bad input (naming the frame when there are
    several)."""
    frames = _check_options(args)
    scene = open_scene(args.blend, args.scene)
    if args.resolution is not None:
        size = parse_resolution(args.resolution, _limits("RenderSettings", "resolution_x"))
        scene.render.resolution_x, scene.render.resolution_y = size
    if args.percentage is not None:
        scene.render.resolution_percentage = args.percentage
    if args.spectral_exr is not None:
        scene.spectral.spectral_exr = True
    if args.device is not None:
        scene.spectral.device = args.device
    for frame in frames or [scene.frame_current]:
        try:
            yield _render_frame(scene, frame, args, written)
        except SpectralError as problem:
            if frames is None or len(frames) == 1:
                raise
            raise SpectralError(f"frame {frame}: {problem}") from None


def _render_frame(scene, frame: int, args, written: list) -> str:
    import bpy

    from .. import output
    from ..jobs.kinds import render_job

    export = export_context_scene(frame)
    region = output.placement(scene)
    job = render_job(scene, export, spp=args.spp, scheduler=args.scheduler)
    bar = None if args.quiet else ProgressBar()
    result = job.run(progress=bar, notice=bar and bar.notice)
    if job.error is not None:
        raise SpectralError(job.error)
    denoised, skipped = output.denoising(scene.spectral)
    for warning in job.warnings + ([skipped] if skipped else []):
        say(f"warning: {warning}", sys.stderr)
    images = output.passes(result.film, region, denoised)
    outputs = [output.exr(frame_path(args.out, frame), images, bpy.context.view_layer.name,
                          output.data_passes(result.passes, region))]
    if args.png is not None:
        alpha = images.alpha if scene.render.film_transparent else None
        outputs.append(image_io.png(frame_path(args.png, frame), images.rgb, scene.view_settings.exposure, alpha))
    if args.spectral_exr is not None:
        if not result.film.bins:
            raise SpectralError(f"--spectral-exr: the {job.describe()} does not make the spectral image yet: render "
                                "with the tracer on this computer")
        outputs.append(output.spectral_exr(frame_path(args.spectral_exr, frame), result.film, export.scene,
                                           region))
    paths = image_io.write_all(outputs)
    written += paths
    spp = scene.spectral.samples if args.spp is None else args.spp
    height, width = images.alpha.shape
    return (f"wrote {', '.join(map(str, paths))} ({width}×{height}, frame {frame}, "
            f"{spp} spp, {job.describe()}, {result.seconds:.1f} s)")


def main(argv=None, prog="python -m addon.cli render") -> int:
    args = _parser(prog).parse_args(argv)
    written = []

    def command():
        for summary in render_blend(args, written):
            say(summary)
        return EXIT_OK

    return run_reporting(command, written)


def _command(argv) -> int:
    """`blender -c spectral_render ...`"""
    try:
        return main(argv, prog=f"blender -c {COMMAND}")
    except SystemExit as exit_:  # argparse: --help or a usage error
        return int(exit_.code or 0)


def register_extras():
    import bpy

    global _handle
    _handle = bpy.utils.register_cli_command(COMMAND, _command)


def unregister_extras():
    import bpy

    global _handle
    bpy.utils.unregister_cli_command(_handle)
    _handle = None


def module_main(argv) -> int:
    """`python -m addon.cli render ...`: registers the add-on in this bpy module first."""
    if not argv or argv[0] != "render":
        print("usage: python -m addon.cli render FILE.blend --out OUT.exr [--scene NAME] [--frame N | --frames LIST] "
              "[--resolution WxH] [--percentage N] [--png OUT.png] [--spectral-exr OUT.exr] [--spp N]",
              file=sys.stderr)
        return 2
    from .. import register

    register()
    return main(argv[1:])

