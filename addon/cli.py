"""Headless rendering of a .blend file to a multilayer EXR.

    python -m addon.cli render FILE.blend --out OUT.exr [--scene NAME] [--frame N] [--spp N] [--scheduler ADDRESS]
    blender -c spectral_render FILE.blend --out OUT.exr [...]   (the same, with the extension installed)

Blender command ids must be Python identifiers, hence `spectral_render`. Exit codes as the tracer's
command line (`addon.tracer.cli`): 0 success, 1 bad input (message on stderr, nothing written),
2 usage error, 70 internal error (a bug, with its traceback), 130 interrupted.
"""

import argparse
import sys
from pathlib import Path

from .tracer import image_io
from .tracer.cli import EXIT_OK, ProgressBar, run_reporting
from .tracer.errors import SpectralError

COMMAND = "spectral_render"
CLASSES = ()
_handle = None


def _parser(prog: str) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=prog, description="Render a .blend file with the spectral volume tracer "
                                     "(or its Cycles emulation, when the scene's Render settings choose it)")
    parser.add_argument("blend", type=Path, help=".blend file to render")
    parser.add_argument("--out", type=Path, required=True, help="multilayer EXR to write (Combined, XYZ, "
                        "XYZ Variance passes, named as F12's)")
    parser.add_argument("--scene", help="scene of the file to render (default: the file's active scene)")
    parser.add_argument("--frame", type=int, help="frame to render (default: the file's current frame)")
    parser.add_argument("--spp", type=int, help="samples per pixel (default: the scene's)")
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
    """Export the context's scene (at `frame`, default its current frame) to a tracer scene."""
    import bpy

    from .export.scene import export_scene

    if frame is not None:
        check_frame(frame)
        bpy.context.scene.frame_set(frame)
    return export_scene(bpy.context.evaluated_depsgraph_get())


def check_frame(frame: int) -> int:
    """`frame`, or a SpectralError when it lies outside the frames Blender has (it would clamp it)."""
    import bpy

    limits = bpy.types.Scene.bl_rna.properties["frame_current"]
    if not limits.hard_min <= frame <= limits.hard_max:
        raise SpectralError(f"--frame: Blender's frames run from {limits.hard_min} to {limits.hard_max}, "
                            f"found {frame}")
    return frame


def render_blend(args) -> str:
    """Open, export, render and write; returns a one-line summary. Raises SpectralError on bad input."""
    import bpy

    from . import dispatch, image_output

    if args.spp is not None and args.spp < 1:
        raise SpectralError(f"--spp must be at least 1, got {args.spp}")
    if args.frame is not None:
        check_frame(args.frame)
    image_io.check_destination(args.out, ".exr")
    scene = open_scene(args.blend, args.scene)
    export = export_context_scene(args.frame)
    region = image_output.placement(scene)
    settings = scene.spectral
    if settings.renderer == "CYCLES":
        result, warnings, how = _emulate(scene, export, args.spp)
    else:
        warnings, how = export.warnings, "tracer"
        scheduler = settings.scheduler_address if args.scheduler is None else args.scheduler
        bar = None if args.quiet else ProgressBar()
        result = dispatch.run(export.scene, scheduler, spp=args.spp, progress=bar, notice=bar and bar.notice)
    for warning in warnings:
        print(f"warning: {warning}", file=sys.stderr)
    film = result.film
    image_io.write_all([image_output.exr(args.out, image_output.passes(film, region), bpy.context.view_layer.name)])
    spp = settings.samples if args.spp is None else args.spp
    return (f"wrote {args.out} ({film.width}×{film.height}, frame {scene.frame_current}, "
            f"{spp} spp, {how}, {result.seconds:.1f} s)")


def _emulate(scene, export, spp):
    """The Cycles emulation of the scene: (result, warnings, description)."""
    from .cycles_emulation.job import emulation_job

    job = emulation_job(scene, export, spp)
    result = job.run()
    if job.error is not None:
        raise SpectralError(job.error)
    return result, job.warnings, f"Cycles emulation: {job.describe()}, each made twice"


def main(argv=None, prog="python -m addon.cli render") -> int:
    args = _parser(prog).parse_args(argv)

    def command():
        print(render_blend(args))
        return EXIT_OK

    return run_reporting(command)


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


def _module_main(argv) -> int:
    """`python -m addon.cli render ...`: registers the add-on in this bpy module first."""
    if not argv or argv[0] != "render":
        print("usage: python -m addon.cli render FILE.blend --out OUT.exr [--scene NAME] [--frame N] [--spp N]",
              file=sys.stderr)
        return 2
    from . import register

    register()
    return main(argv[1:])


if __name__ == "__main__":
    raise SystemExit(_module_main(sys.argv[1:]))
