"""Two versions of the kernel side by side: CPU time, noise per sample and efficiency on the scenes of
`vs_mitsuba`, measured in one run with the versions alternating.

Each version is a checkout of this repository (`git worktree add /tmp/before <revision>` makes one).
Every round runs one fresh process per version, in alternating order (A then B, then B then A, ...), so
that a change in the machine's load hits both alike; each process renders every chosen scene once on
one thread after an untimed warm-up (the kernel compiles, or loads from its cache, first) and reports
the kernel's CPU seconds, the noise per sample (√ of the mean per-pixel variance of Y over the lit
pixels × spp, ÷ their mean Y) and the image's mean Y. Each version keeps its own kernel cache folder
(`--cache-root`), so neither loads the other's kernel. Printed: per scene the medians over the rounds,
the efficiency ratio B/A = (noise_A² · seconds_A) / (noise_B² · seconds_B), and the two mean Y with
their spread over the rounds (they must agree within it, or one version is biased).

    python -m bench.ab /tmp/before .                      # every scene, 96×96 × 32 spp, 8 rounds
    python -m bench.ab /tmp/before . --scenes sun-sphere --rounds 4 --quick
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.vs_mitsuba import FAMILY


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("a", type=Path, help="checkout of version A (the baseline)")
    parser.add_argument("b", type=Path, help="checkout of version B")
    parser.add_argument("--scenes", nargs="+", choices=list(FAMILY), default=list(FAMILY))
    parser.add_argument("--size", type=int, help="image width and height (default 96; quick 48)")
    parser.add_argument("--spp", type=int, help="samples per pixel per round (default 32; quick 8)")
    parser.add_argument("--rounds", type=int, help="rounds per version (default 8; quick 2)")
    parser.add_argument("--quick", action="store_true", help="small and short: proves it runs")
    parser.add_argument("--cache-root", type=Path, default=Path(tempfile.gettempdir()) / "bench-ab-caches",
                        help="folder of the two versions' kernel cache folders")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--seed", type=int, default=1, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    args.size = args.size or (48 if args.quick else 96)
    args.spp = args.spp or (8 if args.quick else 32)
    args.rounds = args.rounds or (2 if args.quick else 8)
    return args


def measure(scenes, size: int, spp: int, seed: int) -> dict:
    """In a worker: scene -> (kernel CPU seconds, noise per sample, mean Y) of this checkout's kernel."""
    from addon.tracer.kernels import numba_backend
    from addon.tracer.lowering import compile_scene

    from bench.measure import render_ours, warm_up
    from bench.scenes import CloudSpec, cloud_scene

    numba_backend.set_threads(1)
    out = {}
    for name in scenes:
        kernel_scene = compile_scene(cloud_scene(CloudSpec(**FAMILY[name]).with_(width=size, height=size)))
        warm_up(kernel_scene)
        start = time.process_time()
        image = render_ours(kernel_scene, spp, seed)
        seconds = time.process_time() - start
        y, variance = image.y, image.variance[..., 1]
        lit = y > 1e-3 * y.max()
        out[name] = (seconds, float(np.sqrt(variance[lit].mean() * spp) / y[lit].mean()), float(y.mean()))
    return out


def run_worker(checkout: Path, cache: Path, args, seed: int) -> dict:
    """One round of one version: a fresh process running this file with the checkout's `addon` and
    `bench` (so a checkout older than this file can be measured)."""
    env = dict(os.environ, PYTHONPATH=str(checkout), SPECTRAL_VOLUME_CACHE_DIR=str(cache),
               SPECTRAL_VOLUME_NO_BACKGROUND_COMPILE="1")
    command = [sys.executable, str(Path(__file__).resolve()), str(checkout), str(checkout), "--worker", "--size",
               str(args.size), "--spp", str(args.spp), "--seed", str(seed), "--scenes", *args.scenes]
    done = subprocess.run(command, cwd=checkout, env=env, capture_output=True, text=True)
    if done.returncode:
        sys.exit(f"{checkout}: the worker failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    args = parse(argv)
    if args.worker:
        print(json.dumps(measure(args.scenes, args.size, args.spp, args.seed)))
        return 0
    from bench.measure import machine

    versions = {"A": args.a.resolve(), "B": args.b.resolve()}
    for label, checkout in versions.items():
        if not (checkout / "addon" / "tracer").is_dir():
            sys.exit(f"{checkout}: not a checkout of this repository (no addon/tracer)")
    caches = {label: args.cache_root / label for label in versions}
    print(machine())
    print(f"A = {versions['A']}\nB = {versions['B']}\n{args.size}×{args.size} × {args.spp} spp, 1 thread, "
          f"{args.rounds} rounds, versions alternating")
    results = {label: {name: [] for name in args.scenes} for label in versions}
    for round_index in range(args.rounds):
        order = ("A", "B") if round_index % 2 == 0 else ("B", "A")
        for label in order:
            for name, values in run_worker(versions[label], caches[label], args, round_index + 1).items():
                results[label][name].append(values)
        print(f"round {round_index + 1} of {args.rounds} done", flush=True)
    print("\n| scene | CPU s A | CPU s B | noise A | noise B | efficiency B/A | mean Y A | mean Y B "
          "| spread of mean Y |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in args.scenes:
        seconds, noise, mean = ({label: [values[k] for values in results[label][name]] for label in versions}
                                for k in range(3))
        median = {label: (statistics.median(seconds[label]), statistics.median(noise[label])) for label in versions}
        ratio = (median["A"][1] ** 2 * median["A"][0]) / (median["B"][1] ** 2 * median["B"][0])
        spread = max(statistics.stdev(mean[label]) if len(mean[label]) > 1 else 0.0 for label in versions)
        print(f"| {name} | {median['A'][0]:.3f} | {median['B'][0]:.3f} | {median['A'][1]:.4f} | {median['B'][1]:.4f} "
              f"| {ratio:.3f} | {statistics.mean(mean['A']):.5f} | {statistics.mean(mean['B']):.5f} | {spread:.5f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
