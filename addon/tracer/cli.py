"""Command line of the tracer: `python -m addon.tracer render|validate SCENE.json ...`.

`render --workers N` renders on N local Dask worker processes, `render --scheduler tcp://HOST:PORT` on
a running Dask scheduler's workers (docs/distributed.md); the image is the same as without them.

Exit codes: 0 success, 1 bad input (a SpectralError, message on stderr; no file written or changed),
2 usage error, 70 internal error (a bug: an unexpected exception, reported with its traceback; no file
written or changed), 130 interrupted (Ctrl-C; nothing is written). A render that has written its files
exits 0 whatever becomes of its messages: stdout and stderr may be closed, full or a broken pipe (`say`).
"""

import argparse
import dataclasses
import json
import math
import os
import sys
import time
import traceback
from pathlib import Path

from . import backends, checks
from .errors import SpectralError
from .progress import TimeLeft
from .scene import SEED_MAX, SPP_MAX
from .validation import check_settings

TIMEOUT_MAX = 86400.0  # seconds (a day): beyond, Dask's and asyncio's timers overflow
# Local worker processes: each is a Python process of its own with a copy of the scene.
WORKERS_MAX = max(256, os.cpu_count() or 1)

EXIT_OK, EXIT_BAD_INPUT, EXIT_USAGE, EXIT_CRASH, EXIT_INTERRUPTED = 0, 1, 2, 70, 130


def say(text: str, stream=None, end: str = "\n") -> bool:
    """Write `text` to `stream` (default: sys.stdout now) and flush; False, and the stream's file pointed at
    the null device, when that fails (a closed, full or broken stream): a lost message must never fail a
    command, nor the interpreter's last flush of the stream turn its exit code into 120."""
    stream = sys.stdout if stream is None else stream
    try:
        stream.write(text + end)
        stream.flush()
        return True
    except (AttributeError, OSError, ValueError):  # None (closed at start), full, broken pipe, closed
        _to_null_device(stream)
        return False


def _to_null_device(stream) -> None:
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, stream.fileno())
        os.close(null)
    except (AttributeError, OSError, ValueError):
        pass


class ProgressBar:
    """A one-line text progress bar on a stream (default: sys.stderr when made), rewritten in place at most
    every `interval` seconds; `notice(text)` writes a line above it. A stream that fails is written no more."""

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
        self._write(f"\r[{'#' * filled}{'.' * (self.width - filled)}] {fraction:6.1%} "
                    f"{elapsed:6.1f}s elapsed{left}", "\n" if fraction >= 1 else "")

    def notice(self, text: str) -> None:
        self._write(text, "\n")

    def _write(self, text: str, end: str) -> None:
        if self.stream is not None and not say(text, self.stream, end):
            self.stream = None


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
    render.add_argument("--backend", choices=backends.NAMES, help="kernel backend (default: the scene's)")
    render.add_argument("--transparent", action="store_true",
                        help="Film ▸ Transparent: camera rays do not see the background; the EXR's and PNG's alpha "
                             "is 1 − the share they saw (default: the scene's render.transparent)")
    render.add_argument("--threads", type=int, help="worker threads for the numba backend")
    render.add_argument("--passes", metavar="NAMES",
                        help="data and light passes to write in the EXR beside the image, comma-separated: Depth, "
                             "Mist, Normal, CryptoObject, CryptoMaterial, Emission, Environment, Volume Direct, "
                             "Volume Indirect (default: the scene's render.passes)")
    render.add_argument("--spectral-exr", type=Path, metavar="PATH",
                        help="also write the spectral image: an EXR with one channel per wavelength bin, in the layout "
                             "of Fichet et al. 2021 (docs/scene-format.md; bins: the scene's render.spectrum_*)")
    for edge, default in (("start", 380), ("end", 780), ("step", 10)):
        render.add_argument(f"--spectrum-{edge}", type=float, metavar="NM",
                            help=f"the spectral EXR's bins' {edge} in nm (default: the scene's, {default} unless set)")
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

    for option, minimum, maximum in (("spp", 1, SPP_MAX), ("threads", 1, None), ("workers", 1, WORKERS_MAX),
                                     ("tile_size", 1, None), ("seed", 0, SEED_MAX)):
        if getattr(args, option) is not None:
            checks.whole_within(getattr(args, option), f"--{option.replace('_', '-')}", minimum, maximum)
    if args.timeout is not None and not (math.isfinite(args.timeout) and 0 < args.timeout <= TIMEOUT_MAX):
        raise SpectralError(f"--timeout: must be a positive number of seconds, at most {TIMEOUT_MAX:g} (a day), "
                            f"found {args.timeout:g}")
    outputs = {"--out": (args.out, ".exr"), "--png": (args.png, ".png"), "--npy": (args.npy, ".npy"),
               "--spectral-exr": (args.spectral_exr, ".exr"), "--stats": (args.stats, None)}
    for path, suffix in outputs.values():
        if path is not None:
            image_io.check_destination(path, suffix)
    image_io.check_distinct((option, path) for option, (path, _) in outputs.items())


def _render(args, written: list) -> int:
    from . import image_io
    from .render import render
    from .scene_io import load_scene

    _check_options(args)
    scene = with_spectrum(with_passes(load_scene(args.scene), args.passes), args)
    if args.transparent:
        scene = dataclasses.replace(scene, settings=dataclasses.replace(scene.settings, transparent=True))
    progress = None if args.quiet else ProgressBar()
    if args.scheduler is not None or args.workers is not None:
        from . import farm

        options = {"tile_size": args.tile_size, "timeout": args.timeout}
        result = farm.render(scene, scheduler=args.scheduler, workers=args.workers, spp=args.spp, seed=args.seed,
                             backend=args.backend, threads=args.threads, progress=progress,
                             **{name: value for name, value in options.items() if value is not None})
    else:
        result = render(scene, spp=args.spp, seed=args.seed, backend=args.backend, threads=args.threads,
                        progress=progress, notice=progress and progress.notice)
    film = result.film
    alpha = film.alpha if scene.settings.transparent else None
    outputs = [image_io.exr(args.out, film.xyz, film.rgb(), film.variance, alpha, data=result.passes)]
    if args.png:
        outputs.append(image_io.png(args.png, film.rgb(), alpha=alpha))
    if args.npy:
        outputs.append(image_io.npy(args.npy, film.xyz))
    if args.spectral_exr:
        from .spectral_film import radiance_units

        outputs.append(image_io.spectral_exr(args.spectral_exr, film.spectrum, film.spectrum_edges,
                                             radiance_units(scene), film.rgb(), alpha))
    if args.stats:
        outputs.append(image_io.text(args.stats, json.dumps(result.stats, indent=2)))
    written += image_io.write_all(outputs)
    say(f"wrote {args.out} ({film.width}×{film.height}, {result.stats['samples_per_pixel']} spp, "
        f"{result.seconds:.1f} s, {result.stats['pixel_samples_per_second']:.0f} pixel-samples/s)")
    return EXIT_OK


def with_passes(scene, names: str | None):
    """`scene` asking for the data and light passes named in `names` (--passes: comma-separated), or as it is."""
    if names is None:
        return scene
    passes = tuple(name.strip() for name in names.split(",") if name.strip())
    settings = dataclasses.replace(scene.settings, passes=passes)
    try:
        check_settings(settings, "render")
    except SpectralError as problem:
        raise SpectralError(f"--passes: {problem}") from None
    return dataclasses.replace(scene, settings=settings)


def with_spectrum(scene, args):
    """`scene` keeping the spectral image, its bins as the --spectrum-* options say, when --spectral-exr asks for
    it; else as it is."""
    if args.spectral_exr is None:
        return scene
    bins = {f"spectrum_{edge}": getattr(args, f"spectrum_{edge}") for edge in ("start", "end", "step")}
    settings = dataclasses.replace(scene.settings, spectrum=True,
                                   **{key: value for key, value in bins.items() if value is not None})
    try:
        check_settings(settings, "render")
    except SpectralError as problem:
        raise SpectralError(f"--spectral-exr: {problem}") from None
    return dataclasses.replace(scene, settings=settings)


def _validate(args) -> int:
    from .scene_io import validate_scene

    for line in validate_scene(args.scene):
        say(line)
    return EXIT_OK


def main(argv=None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command == "render" and args.scheduler is None and args.workers is None:
        if args.tile_size is not None or args.timeout is not None:
            parser.error("--tile-size and --timeout apply to distributed renders: add --scheduler or --workers")
    if args.command == "render" and args.spectral_exr is None:
        if any(getattr(args, f"spectrum_{edge}") is not None for edge in ("start", "end", "step")):
            parser.error("--spectrum-start, --spectrum-end and --spectrum-step set the bins of the spectral EXR: add "
                         "--spectral-exr PATH")
    written = []
    return run_reporting(lambda: _render(args, written) if args.command == "render" else _validate(args), written)


def run_reporting(command, written: list) -> int:
    """`command()`'s exit code, with every failure reported on stderr as its exit code says: bad input
    (SpectralError) as a one-line message, an interruption, or anything else as an internal error.
    `written` holds the paths the command has written so far (they stay): the messages say what they are."""
    try:
        return command()
    except SpectralError as error:
        say(f"error: {error}", sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        say("\ninterrupted: " + ("nothing written" if not written else _written_note(written)), sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as error:  # noqa: BLE001 - a bug, reported as one
        say("".join(traceback.format_exc()), sys.stderr, end="")
        say(f"internal error: {type(error).__name__}: {error}\nThis is a bug in the spectral volume tracer, "
            "not a problem with your input: please report it on the project's issue tracker with the "
            f"command line and the traceback above. {_written_note(written)}", sys.stderr)
        return EXIT_CRASH


def _written_note(written: list) -> str:
    if not written:
        return "Nothing was written."
    return f"Written before that, and kept: {', '.join(map(str, written))}."
