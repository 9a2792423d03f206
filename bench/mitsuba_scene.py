"""Our tracer's `Scene` as a Mitsuba 3 scene dictionary (variant llvm_ad_spectral), for bench/vs_mitsuba.py.

Conversion facts (each checked by `vs_mitsuba.py --check`, which renders both and compares):
- Camera: ours is Blender's (looks along local −z, +y up, +x to the image's right); Mitsuba's sensor looks
  along local +z with +y up and +x to the image's *left*, so its to_world is ours times diag(−1, 1, −1, 1).
  Mitsuba's `fov` with fov_axis "x" is the horizontal angle: 2·atan(extent_x / 2) of our film extent.
- Grid: Mitsuba's VolumeGrid is indexed [z, y, x] and its voxel centres sit at (i + ½)/n of the unit
  cube that `to_world` places; ours is indexed [x, y, z] with cell centres at integer index coordinates
  and zero outside the array (the field fades to 0 over the half cell beyond the outer centres, where
  Mitsuba would clamp to the edge value). So the data is padded with one zero cell on every side and
  transposed, and the unit cube maps to padded index space [−1.5, n + 0.5]³ through our index_to_world.
  The medium's bounding `cube` shape ([−1, 1]³ in Mitsuba) covers the same box, with a `null` BSDF.
- σ_t: ours is density · density_scale · extinction(λ). A flat (grey) extinction becomes Mitsuba's
  `heterogeneous` medium (σ_t = scale · grid, scale = density_scale · extinction) with
  `has_spectral_extinction` false: that flag (read by the medium, default true) tells volpath and
  volpathmis that σ_t is the same at every wavelength, so they skip the per-wavelength transmittance
  and pdf evaluation of a free flight. A varying extinction cannot be a grid volume times a spectrum
  in Mitsuba's plugins (a 3-channel grid is RGB, upsampled to a different spectrum), so it becomes
  `gridspectrum`, a medium written here in Python (registered by `load_mitsuba`): σ_t = scale · grid ·
  the `regular` spectrum of our values, majorant scale · max(grid) · max(spectrum) as in
  `heterogeneous`, with `has_spectral_extinction` true. Dr.Jit traces its Python methods into the same
  kernel as a built-in medium's (on the grey cloud, 48×48, under volpathmis: the same image mean as
  `heterogeneous` and the same time within 2%). `integrator_for` names the integrator that fits:
  `volpathmis` (spectral MIS, which Mitsuba's documentation recommends for spectrally varying
  extinction) when a medium's extinction varies, `volpath` otherwise.
- Lights: our sun's radiometric spectrum (shape scaled so that its luminance Y = strength) is the
  spectral irradiance on a plane facing it, which is what Mitsuba's `directional` `irradiance` is; our
  direction points towards the sun, Mitsuba's along the light's travel (so it is negated). Our
  environment's spectrum (Y = strength) is radiance, as Mitsuba's `constant` `radiance`. Both are passed
  as `regular` spectra with our 1 nm values (250–830 nm), so the two renderers see identical spectra.
- Colour: the film is `hdrfilm` with pixel_format "xyz" and a box filter of radius ½ (each sample
  lands in its own pixel, as in our film). Both normalise XYZ so that a constant radiance 1 has Y = 1.
- Surfaces: each becomes a Mitsuba `Mesh` built in memory with our vertices and triangles (float32 positions),
  its BSDF `diffuse` with our reflectance as a `regular` spectrum, wrapped in `twosided` (Mitsuba's diffuse
  reflects on the front side only; ours on both). Emissive surfaces are not converted: Mitsuba's `area`
  emitter is one-sided, ours two-sided.
- Depth: Mitsuba counts the camera segment as depth 1 and evaluates lights at a scattering vertex only
  while depth < max_depth, so max_depth = ours + 1; null interfaces do not count in either.
"""

import glob
import importlib.util
import os
import re

import numpy as np

from addon.tracer.lights import strength_scale
from addon.tracer.lowering import camera_extent
from addon.tracer.scene import Grid, Medium, Scene, Surface
from addon.tracer.wavelengths import LAMBDA_MAX, LAMBDA_MIN

BLENDER_TO_MITSUBA_CAMERA = np.diag([-1.0, 1.0, -1.0, 1.0])


def spectrum_dict(values: np.ndarray) -> dict:
    """A Mitsuba `regular` spectrum with our 1 nm grid values."""
    return {"type": "regular", "wavelength_min": LAMBDA_MIN, "wavelength_max": LAMBDA_MAX,
            "values": ",".join(f"{float(v):.9g}" for v in values)}


def varies(values: np.ndarray) -> bool:
    """Whether a spectrum's values differ over wavelength (beyond rounding)."""
    values = np.asarray(values, dtype=np.float64)
    return not np.allclose(values, values[0], rtol=1e-9, atol=0.0)


def _constant(values: np.ndarray, what: str) -> float:
    if varies(values):
        raise ValueError(f"{what} varies with wavelength: this converter handles constant {what} only")
    return float(np.asarray(values)[0])


def integrator_for(scene: Scene) -> str:
    """`volpathmis` when some medium's extinction varies with wavelength, else `volpath`."""
    return "volpathmis" if any(varies(medium.extinction.values) for medium in scene.media) else "volpath"


def grid_box(grid: Grid) -> np.ndarray:
    """World matrix of the unit cube [0, 1]³ onto the padded grid's cell extents (see module docstring)."""
    n = np.array(grid.values.shape, dtype=np.float64)
    to_index = np.eye(4)
    to_index[:3, :3] = np.diag(n + 2.0)
    to_index[:3, 3] = -1.5
    return np.asarray(grid.index_to_world, dtype=np.float64) @ to_index


def volume_data(grid: Grid) -> np.ndarray:
    """Our [x, y, z] values, zero-padded by one cell, as Mitsuba's [z, y, x, 1] float32 array."""
    padded = np.pad(np.asarray(grid.values, dtype=np.float32), 1)
    return np.ascontiguousarray(padded.transpose(2, 1, 0))[..., None]


def medium_dicts(mi, medium: Medium, name: str) -> dict:
    if medium.fluorescence is not None or medium.emission is not None or medium.phase != "hg":
        raise ValueError(f"medium {medium.name!r}: only non-emissive, non-fluorescent HG media are converted")
    if medium.albedo_densities.size != 1:
        raise ValueError(f"medium {medium.name!r}: density-dependent albedo is not converted")
    box = grid_box(medium.density)
    unit_to_cube = np.eye(4)  # Mitsuba's cube is [-1, 1]³: map it onto [0, 1]³ first
    unit_to_cube[:3, :3] *= 0.5
    unit_to_cube[:3, 3] = 0.5
    albedo = medium.albedo_table[0]
    extinction = medium.extinction.values
    density = {"type": "gridvolume", "grid": mi.VolumeGrid(volume_data(medium.density)),
               "to_world": mi.ScalarTransform4f(box.tolist()), "filter_type": "trilinear"}
    phase = {"type": "hg", "g": _constant(medium.anisotropy.values, "anisotropy")}
    if varies(extinction):
        interior = {"type": "gridspectrum", "density": density, "scale": medium.density_scale,
                    "extinction": spectrum_dict(extinction), "extinction_max": float(np.max(extinction)),
                    "albedo": spectrum_dict(albedo), "phase": phase}
    else:
        interior = {"type": "heterogeneous", "sigma_t": density, "scale": medium.density_scale * float(extinction[0]),
                    "has_spectral_extinction": False,
                    "albedo": spectrum_dict(albedo) if varies(albedo) else float(albedo[0]), "phase": phase}
    return {"type": "cube", "to_world": mi.ScalarTransform4f((box @ unit_to_cube).tolist()), "bsdf": {"type": "null"},
            "interior": interior}


def light_dict(light) -> dict:
    spd = light.spectrum.values * strength_scale(light)
    if light.kind == "sun":
        if light.angle > 0:
            raise ValueError("a sun with an angular diameter has no Mitsuba `directional` equivalent")
        direction = -np.asarray(light.direction, dtype=np.float64)
        return {"type": "directional", "direction": (direction / np.linalg.norm(direction)).tolist(),
                "irradiance": spectrum_dict(spd)}
    if light.kind == "environment":
        return {"type": "constant", "radiance": spectrum_dict(spd)}
    raise ValueError(f"light kind {light.kind!r} is not converted")


def surface_mesh(mi, surface: Surface):
    """A Mitsuba mesh of `surface` with a two-sided diffuse BSDF of its reflectance (see the module docstring)."""
    if surface.emission is not None:
        raise ValueError(f"surface {surface.name!r}: emissive surfaces are not converted (Mitsuba's area emitter is "
                         "one-sided)")
    vertices = np.asarray(surface.vertices, dtype=np.float32)
    triangles = np.asarray(surface.triangles, dtype=np.uint32)
    props = mi.Properties()
    props["bsdf"] = mi.load_dict({"type": "twosided", "material": {
        "type": "diffuse", "reflectance": spectrum_dict(surface.reflectance.values)}})
    mesh = mi.Mesh(surface.name, vertex_count=len(vertices), face_count=len(triangles), props=props,
                   has_vertex_normals=False, has_vertex_texcoords=False)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(vertices.ravel())
    params["faces"] = mi.UInt(triangles.ravel())
    params.update()
    return mesh


def scene_dict(mi, scene: Scene, integrator: str | None = None, spp: int = 1) -> dict:
    """The Mitsuba scene dictionary of `scene` (see the module docstring), rendered with `integrator`
    (default: `integrator_for(scene)`); `mi` is the mitsuba module from `load_mitsuba`."""
    camera = scene.camera
    if camera.kind != "perspective" or camera.shift_x or camera.shift_y:
        raise ValueError("only unshifted perspective cameras are converted")
    extent_x = camera_extent(camera)[0]
    to_world = np.asarray(camera.to_world, dtype=np.float64) @ BLENDER_TO_MITSUBA_CAMERA
    settings = scene.settings
    result = {
        "type": "scene",
        "integrator": {"type": integrator or integrator_for(scene), "max_depth": settings.max_depth + 1,
                       "rr_depth": settings.rr_depth},
        "sensor": {
            "type": "perspective",
            "fov_axis": "x",
            "fov": float(np.degrees(2.0 * np.arctan(0.5 * extent_x))),
            "to_world": mi.ScalarTransform4f(to_world.tolist()),
            "film": {"type": "hdrfilm", "width": camera.width, "height": camera.height, "pixel_format": "xyz",
                     "rfilter": {"type": "box"}, "sample_border": False},
            "sampler": {"type": "independent", "sample_count": spp},
        },
    }
    for index, medium in enumerate(scene.media):
        result[f"medium_{index}"] = medium_dicts(mi, medium, f"medium_{index}")
    for index, light in enumerate(scene.lights):
        result[f"light_{index}_{light.kind}"] = light_dict(light)
    for index, surface in enumerate(scene.surfaces):
        result[f"surface_{index}"] = surface_mesh(mi, surface)
    return result


VARIANT = "llvm_ad_spectral"
MIN_LLVM = 19  # Dr.Jit 1.5's kernels crash LLVM 15 ("Cannot select: fminimum"); Debian's libllvm19 works


def _llvm_libraries() -> list[tuple[int, str]]:
    """(major version, path) of the LLVM shared libraries where Dr.Jit looks for them, newest first."""
    found = []
    for path in glob.glob("/usr/lib/*/libLLVM*.so*") + glob.glob("/usr/lib/llvm-*/lib/libLLVM*.so*"):
        match = re.search(r"libLLVM(?:-(\d+)|\.so\.(\d+))", path)
        if match:
            found.append((int(match.group(1) or match.group(2)), path))
    return sorted(set(found), reverse=True)


def load_mitsuba():
    """The mitsuba module with variant llvm_ad_spectral set, or SystemExit with what to do.

    Dr.Jit picks an LLVM library by itself unless DRJIT_LIBLLVM_PATH names one; here the newest one
    found is named explicitly when it is new enough, so an older LLVM lying beside it is never used."""
    if importlib.util.find_spec("mitsuba") is None:
        raise SystemExit("Mitsuba is not installed: run `make bench` (it installs requirements.lock)")
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        libraries = _llvm_libraries()
        if not libraries or libraries[0][0] < MIN_LLVM:
            have = ", ".join(path for _, path in libraries) or "none"
            raise SystemExit(f"Mitsuba's LLVM backend needs LLVM >= {MIN_LLVM} (found: {have}). Run `make bench`, "
                             f"or `apt-get install -y libllvm19`, or set DRJIT_LIBLLVM_PATH to a libLLVM.so")
        os.environ["DRJIT_LIBLLVM_PATH"] = libraries[0][1]
    import mitsuba as mi

    mi.set_variant(VARIANT)
    _register_gridspectrum(mi)
    return mi


def _register_gridspectrum(mi) -> None:
    """Register the `gridspectrum` medium (see the module docstring) for the variant now set."""
    import drjit as dr

    class GridSpectrumMedium(mi.Medium):
        def __init__(self, props):
            super().__init__(props)
            self.density, self.extinction, self.albedo = props["density"], props["extinction"], props["albedo"]
            self.scale = props["scale"]
            self.majorant = mi.Float(self.scale * self.density.max() * props["extinction_max"])
            self.m_is_homogeneous, self.m_has_spectral_extinction = False, True

        def get_majorant(self, mei, active=True):
            return mi.UnpolarizedSpectrum(self.majorant)

        def get_scattering_coefficients(self, mei, active=True):
            si = dr.zeros(mi.SurfaceInteraction3f)  # spectra are evaluated at an interaction's wavelengths
            si.wavelengths = mei.wavelengths
            sigma_t = self.scale * self.density.eval_1(mei, active) * self.extinction.eval(si, active)
            return sigma_t * self.albedo.eval(si, active), self.get_majorant(mei, active) - sigma_t, sigma_t

        def intersect_aabb(self, ray):
            return self.density.bbox().ray_intersect(ray)

    mi.register_medium("gridspectrum", GridSpectrumMedium)
