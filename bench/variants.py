"""What-if timings of changes to the kernel, measured on copies of it (bench/kernel_copy.py) against the
real one: evidence for the Performance changes proposed in bench/README.md. The tracer is not modified.

Variants:
- inline: every helper that takes the kernel scene (`_coefficients`, `_density`, `_albedo`, the tracker,
  light and phase helpers, `_transmittance`, `_next_event`) compiled with `inline="always"`. The kernel
  scene is a named tuple of ~40 arrays; each call of a non-inlined helper increments and decrements the
  reference count of every one of them (atomic operations on counters that all threads share). Same
  paths, same image: only the time changes.
- albedo: at a real collision the path scatters with probability σ_t/σ̄ and its weight is multiplied by
  the albedo σ_s/σ_t, instead of ending in an absorption with probability σ_a/σ̄ (analog absorption);
  Russian roulette ends paths instead. Different paths, same expectation: compared by efficiency.

Each variant renders the benchmark cloud for the same time as the real kernel (interleaved passes);
printed: time per sample, MSE per sample (MSE · spp, against a long reference of the real kernel) and
efficiency = 1 / (MSE · seconds), each as variant / tracer. Each copy is compiled once (minutes) and then
cached in out/bench-cache/.

    python -m bench.variants             # 64³ g 0.6, 128×128, reference 1024 spp, 10 s per kernel
    python -m bench.variants --quick     # 48×48, reference 256 spp, 2 s
"""

import argparse
import re

import numpy as np

from bench.kernel_copy import CopyRenderer, compile_copy, kernel_copy
from bench.measure import (OurRenderer, compile_timed, corrected_mse, efficiency, equal_time, machine,
                           reference_noise, render_ours, warm_up)
from bench.scenes import CACHE, CloudSpec, cloud_scene

ANALOG_ABSORPTION = """            if choice < sigma_a[0]:
                event = EVENT_ABSORB
                break
            if choice < sigma_a[0] + sigma_s[0]:
                probability0 = sigma_s[0] / total
                for i in range(n):
                    beta[i] *= sigma_s[i] / sigma_bar / probability0
                    r_u[i] *= sigma_s[i] / (sigma_bar + sigma_fl[i]) / probability0
"""
ALBEDO_WEIGHTING = """            if choice < sigma_a[0] + sigma_s[0]:
                probability0 = (sigma_a[0] + sigma_s[0]) / total
                for i in range(n):
                    beta[i] *= sigma_s[i] / sigma_bar / probability0
                    r_u[i] *= (sigma_a[i] + sigma_s[i]) / (sigma_bar + sigma_fl[i]) / probability0
"""
NOT_INLINED = ("_trace_path", "_trilinear")  # the big one, and the one that takes no kernel scene


def inline_replacements() -> list[tuple[str, str]]:
    from addon.tracer.kernels import numba_backend
    import inspect

    source = inspect.getsource(numba_backend)
    return [(match.group(0), match.group(0).replace("@njit\n", '@njit(inline="always")\n'))
            for match in re.finditer(r"^@njit\ndef (\w+)\(", source, re.M) if match.group(1) not in NOT_INLINED]


VARIANTS = {
    "inline": inline_replacements,
    "albedo": lambda: [(ANALOG_ABSORPTION, ALBEDO_WEIGHTING)],
    "inline+albedo": lambda: inline_replacements() + [(ANALOG_ABSORPTION, ALBEDO_WEIGHTING)],
}


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true", help="48×48, reference 256 spp, 2 s per kernel")
    parser.add_argument("--variants", nargs="+", choices=list(VARIANTS), default=["inline", "albedo"])
    parser.add_argument("--resolution", type=int, default=64)
    parser.add_argument("--g", type=float, default=0.6)
    parser.add_argument("--width", type=int)
    parser.add_argument("--height", type=int)
    parser.add_argument("--reference-spp", type=int)
    parser.add_argument("--seconds", type=float, help="budget per kernel and variant (default 10)")
    parser.add_argument("--threads", type=int, help="Numba threads (default: all)")
    args = parser.parse_args(argv)
    args.width = args.width or (48 if args.quick else 128)
    args.height = args.height or (48 if args.quick else 128)
    args.reference_spp = args.reference_spp or (256 if args.quick else 1024)
    args.seconds = args.seconds or (2.0 if args.quick else 10.0)
    return args


def main(argv=None) -> int:
    args = parse(argv)
    if args.threads:
        import numba

        numba.set_num_threads(args.threads)
    print(f"machine: {machine()}" + ("\n[QUICK MODE: figures are not representative]" if args.quick else ""))
    spec = CloudSpec(resolution=args.resolution, g=args.g, width=args.width, height=args.height)
    kernel_scene, _ = compile_timed(cloud_scene(spec, seed=0))
    warm_up(kernel_scene)
    reference = render_ours(kernel_scene, args.reference_spp, seed=1000)
    noise = reference_noise(reference, 1)
    print(f"{spec.label()}: reference = tracer at {reference.spp} spp ({reference.seconds:.1f} s)")
    for index, name in enumerate(args.variants):
        module = kernel_copy(name.replace("+", "_"), CACHE, VARIANTS[name]())
        print(f"\n{name}: copy compiled or loaded in {compile_copy(module, kernel_scene):.1f} s (not timed)")
        same = np.allclose(render_ours(kernel_scene, 1, seed=5).xyz,
                           CopyRenderer(module, kernel_scene, 5).render(1).xyz, rtol=1e-9, atol=1e-12)
        print(f"  same image as the tracer for the same samples: {'yes' if same else 'no (different paths)'}")
        images = equal_time({"tracer": OurRenderer(kernel_scene, seed=20 + index),
                             name: CopyRenderer(module, kernel_scene, seed=40 + index)}, args.seconds)
        figures = {}
        for key, image in images.items():
            mse = corrected_mse(image.y, reference.y, noise)
            figures[key] = (image.seconds / image.spp, mse * image.spp, efficiency(mse, image.seconds))
            print(f"  {key:14s} {image.spp:5d} spp in {image.seconds:6.2f} s: {figures[key][0] * 1e3:8.2f} ms/spp, "
                  f"MSE·spp (Y) {figures[key][1]:.5f}, efficiency {figures[key][2]:.4g}, mean Y {image.y.mean():.4f} "
                  f"(reference {reference.y.mean():.4f})")
        (t0, v0, e0), (t1, v1, e1) = figures["tracer"], figures[name]
        print(f"  {name} / tracer: speed per sample {t0 / t1:.2f}×, MSE per sample {v1 / v0:.2f}×, "
              f"efficiency {e1 / e0:.2f}×")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
