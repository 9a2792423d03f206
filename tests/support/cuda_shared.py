"""Every shared leaf function (`shared_math.shared` / `shared_inline`) with the Numba types the kernels call it
with, kept in one place for the CUDA tests (tests/tracer/kernels/test_cuda_shared.py) and the compile bench
(bench/cuda_compile.py): one path's scalars (float64, int64, uint64 for the random streams), the kernel scene
as the Numba kernel types it (`KernelScene` of arrays), a wavelength located by `lookups.on_grid`, a table
or a row of one.
"""

import ast
from pathlib import Path

from addon.tracer import binned, phase, planck
from addon.tracer.kernels import (
    dda, envmap, estimator, fluorescent_reservoir, geometry, light_sampling, light_split, lookups, media, rng,
    spectrum_bins, surfaces, transparency)
from addon.tracer.lowering import compile_scene
from tests.support import scenes as s

TRACER = Path(binned.__file__).parent
MODULES = (lookups, geometry, media, light_sampling, envmap, surfaces, dda, rng, transparency, fluorescent_reservoir,
           light_split, spectrum_bins, estimator, phase, binned, planck)


def shared_in_sources():
    """(module, name) of every function the tracer's sources decorate `@shared` or `@shared_inline`, but the Numba
    kernel's path functions (`kernels/numba_backend.py`), which compile for CUDA as one kernel, the CUDA backend's
    (tests/tracer/kernels/test_cuda_backend.py)."""
    found = set()
    for path in sorted(set(TRACER.rglob("*.py")) - {TRACER / "kernels" / "numba_backend.py"}):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and any(
                    isinstance(d, ast.Name) and d.id in ("shared", "shared_inline") for d in node.decorator_list):
                found.add((path.relative_to(TRACER).with_suffix("").as_posix().replace("/", "."), node.name))
    return found


def kernel_scene():
    """A small kernel scene: its Numba type is that of every scene's (the arrays' dtypes and ranks are fixed)."""
    return compile_scene(s.scene(s.ortho_camera(), [s.medium(s.box_grid())], [s.sun([0, 0, 1], 3.0)]))


def signatures(types=None, typeof=None):
    """{function: argument types} for every shared function, as the Numba kernel calls it: Numba's types, or
    those of another compiler's type system (`types` module and `typeof`; numba-cuda-mlir has its own)."""
    if types is None:
        from numba import types, typeof
    ks = kernel_scene()
    KS = typeof(ks)
    F, I, U, B = types.float64, types.int64, types.uint64, types.boolean
    A1, A2 = types.float64[::1], types.float64[:, ::1]
    AT = types.Tuple((I, F, types.boolean))  # a wavelength located on the grid (`on_grid`)
    V3 = types.UniTuple(F, 3)
    return {
        lookups.on_grid: (F,),
        lookups.evenly_spaced_at: (A1, F, F, F),
        lookups.table_at: (A2, I, AT),
        lookups._corners: (F, I, I),
        lookups.trilinear: (typeof(ks.density.data), I, typeof(ks.density.shape[0]), F, F, F),
        lookups.cdf_bin: (A1, I, I, F),
        lookups.probe_chance: (KS, F, F, F),
        geometry.transform_point: (A2, F, F, F),
        geometry.transform_vector: (A2, F, F, F),
        geometry.normalize: (F, F, F),
        geometry.camera_ray: (KS, I, I, F, F),
        geometry.camera_depths: (A2, I, F, F, F, F),
        media.density: (KS, I, F, F, F),
        media.temperature: (KS, I, F, F, F),
        media.albedo: (KS, I, F, AT),
        media.attenuation: (F, F, F),
        media.collision_coefficients: (F, F, F, F, F, F),
        media.thermal_emission: (F, F, F),
        media.blackbody_normalisation: (KS, F),
        media.glow_emission: (F, F, F, F, F),
        media.phase_pdf: (KS, I, F, F),
        media.free_path: (F, F),
        media.null_fraction: (F, F, F),
        light_sampling.choose_light: (A1, F),
        light_sampling.is_delta: (KS, I),
        light_sampling.sun_solid_angle: (KS, I),
        light_sampling.in_sun_cone: (KS, I, F, F, F),
        light_sampling.infinite_radiance: (KS, I, AT, F, F, F),
        light_sampling.infinite_pdf: (KS, I, F, F, F),
        light_sampling.uniform_area_point: (KS, I, F, F),
        light_sampling._angle: (F,),
        light_sampling._rectangle_frame: (KS, I, F, F, F),
        light_sampling._rectangle_angles: (F, F, F, F, F),
        light_sampling.rectangle_solid_angle: (KS, I, F, F, F),
        light_sampling.spherical_rectangle_point: (KS, I, F, F, F, F, F),
        light_sampling.area_light_area: (KS, I),
        light_sampling._by_solid_angle: (F,),
        light_sampling._sampled_pdf: (KS, I, F, F, F),
        light_sampling.area_direction_pdf: (KS, I, F, F, F, F, F),
        light_sampling.area_light_hit: (KS, I, F, F, F, F, F, F, F),
        light_sampling.area_radiance: (KS, I, AT),
        light_sampling.area_point: (KS, I, F, F, F, F, F),
        light_sampling.sample_light: (KS, I, F, F, F, F, F),
        light_sampling.incident_radiance: (KS, I, AT, F, F, F, F),
        envmap.row_solid_angle: (I, I, I),
        envmap.texel_of: (KS, I, F, F, F),
        envmap.texel_pdf: (KS, I, I, I),
        envmap.envmap_radiance: (KS, I, AT, F, F, F),
        envmap.envmap_pdf: (KS, I, F, F, F),
        envmap.envmap_sample: (KS, I, F, F),
        surfaces.triangle_distance: (KS, I, F, F, F, F, F, F),
        surfaces.facing_normal: (KS, I, F, F, F),
        surfaces.barycentrics: (KS, I, F, F, F),
        surfaces._texel_index: (I, I, I),
        surfaces.texel_colour: (KS, I, I, F, F, F),
        surfaces._lattice: (F,),
        surfaces._srgb_decoded: (F, types.boolean),
        surfaces.rgb_reflectance: (A2, F, F, F, AT),
        surfaces.offset_point: (F, F, F, F, F, F),
        surfaces.lambert_pdf: (F,),
        surfaces.lambert_sample_cos: (F,),
        surfaces.emitter_point: (KS, I, F, F),
        surfaces.emitter_pdf: (F, F, F),
        dda.axis_span: (F, F, F, F, F),
        dda.axis_entry: (F, F, F, I, I),
        rng.mix64: (U,),
        rng.pixel_key: (I, I, I),
        rng.path_key: (U, I),
        rng.uniform: (U, U),
        rng.reverse_bits32: (U,),
        rng.nested_scramble: (U, U),
        rng.sobol: (U, U),
        rng.low_discrepancy: (U, U, U),
        transparency.transparency_weight: (KS, F, F, I),
        light_split.clamp_factor: (F, F, F, A2, F),
        light_split.clamped_mark: (F, F, F, F),
        light_split.direct_slot: (I,),
        spectrum_bins.spectrum_bin: (A1, F),
        spectrum_bins.spectrum_weight: (A1, F, F, I),
        estimator.companion_uniform: (F, I, I),
        estimator.camera_estimate: (F, F, I),
        estimator.collision_estimate: (F, F, F),
        estimator.real_probability: (F, F, F),
        estimator.real_collision: (F, F, F, F, F, F),
        estimator.null_collision: (F, F, F, F, F, F, F, B),
        estimator.ratio_tracked: (F, F, F, F, B),
        estimator.controls_transmittance: (F,),
        estimator.residual_tracked: (F, F),
        estimator.shadow_bound: (F, F),
        estimator.shadow_roulette: (F, F),
        estimator.attenuates_alike: (F, F),
        estimator.light_sample_ratio: (F, F, F, F, B),
        estimator.next_event_contribution: (F, F, F, F, F),
        estimator.hit_light_ratio: (F, F, F, F, B),
        estimator.hit_light_contribution: (F, F, F, B, F),
        estimator.phase_sampled: (F, F, F, F),
        estimator.lambert_sampled: (F, F, F, F),
        estimator.probe_sampled: (F, F, F, F, F),
        estimator.probe_weight: (F, F, F),
        estimator.roulette_survival: (F,),
        fluorescent_reservoir.front_guide: (F,),
        fluorescent_reservoir.back_guide: (F,),
        fluorescent_reservoir.chosen_reservoir: (F,),
        fluorescent_reservoir.mixture_weight: (F, F, F, F),
        phase.hg_pdf: (F, F),
        phase.hg_sample_cos: (F, F),
        phase.rayleigh_pdf: (F,),
        phase.rayleigh_sample_cos: (F,),
        phase.isotropic_pdf: (F,),
        phase.orthonormal_basis: (V3,),
        phase.sample_direction: (V3, F, F),
        binned.sample_binned: (A1, F),
        binned.pdf_binned: (A1, F),
        binned.linear_over_binned: (A1, F),
        planck.planck_radiance: (F, F),
    }


def listed(functions):
    """(module, name) of `functions`, as `shared_in_sources` names them."""
    return {(f.__module__.removeprefix("addon.tracer."), f.__name__) for f in functions}
