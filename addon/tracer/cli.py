"""Command line of the tracer: `python -m addon.tracer render|validate SCENE.json ...`.

`render --workers N` renders on N local Dask worker processes, `render --scheduler tcp://HOST:PORT` on
a running Dask scheduler's workers (docs/distributed.md); the image is the same as without them.

Exit codes: 0 success, 1 bad input (a SpectralError, message on stderr; no file written or changed),
2 usage error, 70 internal error (a bug: an unexpected exception, reported with its traceback; no file
written or changed), 130 interrupted (Ctrl-C; nothing is written).
"""

import argparse
import json
import math
import sys
import time
import traceback
from pathlib import Path

from . import checks
from .errors import SpectralError
from .progress import TimeLeft
from .scene import BACKENDS, SEED_MAX

EXIT_OK, EXIT_BAD_INPUT, EXIT_USAGE, EXIT_CRASH, EXIT_INTERRUPTED = 0, 1, 2, 70, 130


class ProgressBar:
    """A one-line text progress bar on a stream (default: sys.stderr when made), rewritten in place at most
    every `interval` seconds; `notice(text)` writes a line above it."""

    def __init__(self, stream=None, width: int = 30, interval: float = 0.1):
        self.stream, self.width, self.start = stream or sys.stderr, width, time.perf_counter()
        self.interval, self.shown = interval, -interval
        self.time_left = TimeLeft()

    def __call__(self, _film, fraction: float) -> None:
        elapsed = time.perf_counter() - self.start
        remaining = self.time_left(fraction)
        if elapsed - self.shown < self.interval and fraction < 1:
            return
        self.shown = elapsed
        filled = int(round(fraction * self.width))
        left = "" if remaining is None else f", ~{remaining:5.1f}s left"
        self.stream.write(f"\r[{'#' * filled}{'.' * (self.width - filled)}] {fraction:6.1%} "
                          f"{elapsed:6.1f}s elapsed{left}")
        if fraction >= 1:
            self.stream.write("\n")
        self.stream.flush()

    def notice(self, text: str) -> None:
        self.stream.write(f"{text}\n")
        self.stream.flush()


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m addon.tracer", description="Spectral volume path tracer")
    commands = parser.add_subparsers(dest="command", required=True)
    render = commands.add_parser("render", help="render a scene file to images")
    render.add_argument("scene", type=Path, help="scene.json (see docs/scene-format.md)")
    render.add_argument("--out", type=Path, required=True, help="multilayer EXR to write (passes Combined, XYZ, "
                        "XYZ Variance, named as Blender's F12 names them)")
    render.add_argument("--png", type=Path, help="also write a PNG preview (Standard view)")
    render.add_argument("--npy", type=Path, help="also write XYZ as a float32 .npy array (height, width, 3)")
    render.add_argument("--spp", type=int, help="samples per pixel (default: the scene's)")
    render.add_argument("--seed", type=int, help="random seed (default: the scene's)")
    render.add_argument("--backend", choices=BACKENDS, help="kernel backend (default: the scene's)")
    render.add_argument("--threads", type=int, help="worker threads for the numba backend")
    render.add_argument("--stats", type=Path, help="write timing, samples per second and mean XYZ as JSON")
    render.add_argument("--quiet", action="store_true", help="no progress bar")
    farm = render.add_mutually_exclusive_group()
    farm.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                      help="render on the workers of this Dask scheduler (docs/distributed.md)")
    farm.add_argument("--workers", type=int, metavar="N", help="render on N local Dask worker processes")
    render.add_argument("--tile-size", type=int, metavar="PIXELS",
                        help="tile edge of a distributed task in pixels (default: 64)")
    render.add_argument("--timeout", type=float, metavar="SECONDS",
                        help="give up on an unreachable scheduler, or one without workers, after this long "
                             "(default: 10)")
    validate = commands.add_parser("validate", help="check a scene file and summarise it")
    validate.add_argument("scene", type=Path)
    return parser


def _check_options(args) -> None:
    """The render options' values and every output's destination, before any work is done."""
    from . import image_io

    for option, minimum in (("spp", 1), ("threads", 1), ("workers", 1), ("tile_size", 1)):
        if getattr(args, option) is not None:
            checks.whole_within(getattr(args, option), f"--{option.replace('_', '-')}", minimum)
    if args.seed is not None:
        checks.whole_within(args.seed, "--seed", 0, SEED_MAX)
    if args.timeout is not None and not (math.isfinite(args.timeout) and args.timeout > 0):
        raise SpectralError(f"--timeout: must be a positive number of seconds, found {args.timeout:g}")
    outputs = {"--out": (args.out, ".exr"), "--png": (args.png, ".png"), "--npy": (args.npy, ".npy"),
               "--stats": (args.stats, None)}
    for path, suffix in outputs.values():
        if path is not None:
            image_io.check_destination(path, suffix)
    image_io.check_distinct((option, path) for option, (path, _) in outputs.items())


def _render(args) -> int:
    from . import image_io
    from .render import render
    from .scene_io import load_scene

    _check_options(args)
    scene = load_scene(args.scene)
    progress = None if args.quiet else ProgressBar()
    if args.scheduler is not None or args.workers is not None:
        from . import distributed

        options = {"tile_size": args.tile_size, "timeout": args.timeout}
        result = distributed.render(scene, scheduler=args.scheduler, workers=args.workers, spp=args.spp,
                                    seed=args.seed, backend=args.backend, threads=args.threads, progress=progress,
                                    **{name: value for name, value in options.items() if value is not None})
    else:
        result = render(scene, spp=args.spp, seed=args.seed, backend=args.backend, threads=args.threads,
                        progress=progress, notice=progress and progress.notice)
    film = result.film
    outputs = [image_io.exr(args.out, film.xyz, film.rgb(), film.variance)]
    if args.png:
        outputs.append(image_io.png(args.png, film.rgb()))
    if args.npy:
        outputs.append(image_io.npy(args.npy, film.xyz))
    if args.stats:
        outputs.append(image_io.text(args.stats, json.dumps(result.stats, indent=2)))
    image_io.write_all(outputs)
    print(f"wrote {args.out} ({film.width}×{film.height}, {result.stats['samples_per_pixel']} spp, "
          f"{result.seconds:.1f} s, {result.stats['pixel_samples_per_second']:.0f} pixel-samples/s)")
    return EXIT_OK


def _validate(args) -> int:
    from .scene_io import validate_scene

    for line in validate_scene(args.scene):
        print(line)
    return EXIT_OK


def main(argv=None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command == "render" and args.scheduler is None and args.workers is None:
        if args.tile_size is not None or args.timeout is not None:
            parser.error("--tile-size and --timeout apply to distributed renders: add --scheduler or --workers")
    return run_reporting(lambda: _render(args) if args.command == "render" else _validate(args))


def run_reporting(command) -> int:
    """`command()`'s exit code, with every failure reported on stderr as its exit code says: bad input
    (SpectralError) as a one-line message, an interruption, or anything else as an internal error."""
    try:
        return command()
    except SpectralError as error:
        print(f"error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("\ninterrupted: nothing written", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as error:  # noqa: BLE001 - a bug, reported as one
        traceback.print_exc()
        print(f"internal error: {type(error).__name__}: {error}\nThis is a bug in the spectral volume tracer, "
              "not a problem with your input: please report it on the project's issue tracker with the "
              "command line and the traceback above. Nothing was written.", file=sys.stderr)
        return EXIT_CRASH
