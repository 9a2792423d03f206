"""Render settings (per Scene) and per-object volume settings."""

import bpy

from ..cycles_emulation.band_plan import DEFAULT_MAX_RENDERS, TARGET_DELTA_E
from ..tracer.scene import RenderSettings
from ..tracer.wavelengths import LAMBDA_MAX, LAMBDA_MIN

DEFAULTS = RenderSettings()
ENGINE_ID = "SPECTRAL_VOLUME"  # the render engine's bl_idname; its panels show while it is the engine
GPU_BACKEND = "cuda"  # the tracer backend (tracer/backends.py) that Device ▸ GPU Compute renders with


def chosen_backend(settings) -> str:
    """The tracer backend the Render settings choose: the GPU's for Device ▸ GPU Compute, else the CPU backend
    chosen under Performance."""
    return GPU_BACKEND if settings.device == "GPU" else settings.backend


class SpectralRenderSettings(bpy.types.PropertyGroup):
    """Per-scene render settings of the spectral tracer (mirrors addon.tracer.scene.RenderSettings)."""

    samples: bpy.props.IntProperty(name="Samples", description="Paths per pixel", default=64, min=1, soft_max=4096)
    preview_samples: bpy.props.IntProperty(
        name="Viewport Samples", default=32, min=1, soft_max=4096,
        description="Paths per pixel of the Rendered viewport: it refines its image up to this many, then stops")
    use_adaptive_sampling: bpy.props.BoolProperty(
        name="Adaptive Sampling", default=True,
        description="Stop sampling each pixel once its noise is below the Noise Threshold, as Cycles' adaptive "
                    "sampling does (F12, Render to Image, command line; the viewport and a render farm take every sample)")
    adaptive_threshold: bpy.props.FloatProperty(
        name="Noise Threshold", default=0.01, min=0.0001, max=1.0, soft_min=0.001, precision=4, step=0.1,
        description="How quiet a pixel must be to stop: the sum of its R, G and B standard errors over the square "
                    "root of R + G + B (lower: less noise, more time)")
    adaptive_min_samples: bpy.props.IntProperty(
        name="Min Samples", default=DEFAULTS.min_samples, min=0, soft_max=4096,
        description="Samples every pixel takes before it may stop; 0 chooses them from the Noise Threshold "
                    "(64 at 0.01)")
    denoise: bpy.props.BoolProperty(
        name="Denoise", default=True,
        description="Denoise the final image (F12, Render to Image, command line) with Intel Open Image Denoise: "
                    "the Combined pass and PNGs only; the XYZ and XYZ Variance passes stay as rendered")
    viewport_denoise: bpy.props.BoolProperty(
        name="Viewport Denoise", default=False,
        description="Denoise the Rendered viewport's image with Intel Open Image Denoise once it shows the full "
                    "resolution")
    seed: bpy.props.IntProperty(name="Seed", description="Random seed: the same seed gives the same image",
                                default=DEFAULTS.seed, min=0)
    max_bounces: bpy.props.IntProperty(name="Max Bounces", description="Most scattering events along a path",
                                       default=DEFAULTS.max_depth, min=1, soft_max=1024)
    # Light Paths ▸ Clamping, with Cycles' defaults (the scene file's are 0: no clamping)
    clamp_direct: bpy.props.FloatProperty(
        name="Direct Light", default=0.0, min=0.0, soft_max=100.0,
        description="Largest light a sample may bring from emitters the camera sees and from lights reaching the "
                    "first bounce through next-event estimation (mean of linear R, G and B), as Cycles clamps it: "
                    "brighter samples are scaled down, which removes fireflies but darkens the image. 0: no clamping")
    clamp_indirect: bpy.props.FloatProperty(
        name="Indirect Light", default=10.0, min=0.0, soft_max=100.0,
        description="Largest light a sample may bring after its first bounce (mean of linear R, G and B), as "
                    "Cycles clamps it: brighter samples are scaled down, which removes fireflies but darkens the "
                    "image. 0: no clamping")
    # Light Paths ▸ Clamping ▸ Firefly Filter (the scene file's default is 0: off)
    use_firefly_filter: bpy.props.BoolProperty(
        name="Firefly Filter", default=True,
        description="Scale down each pixel's brightest samples where they stand out from its neighbours' samples (a "
                    "rare path that alone would make a speck): removes the fireflies of a few samples; it darkens "
                    "the image a little at low sample counts and less as they grow")
    firefly_threshold: bpy.props.FloatProperty(
        name="Firefly Threshold", default=2.0, min=0.01, soft_max=10.0, precision=2, step=10,
        description="How far above its neighbours a sample may be, in their standard errors (lower: fewer "
                    "fireflies, a darker image at low sample counts)")
    bands: bpy.props.IntProperty(name="Bands", description="Render the wavelength range in this many passes",
                                 default=DEFAULTS.bands, min=1, soft_max=64)
    wavelength_sampling: bpy.props.EnumProperty(
        name="Wavelength Sampling", description="How each path's wavelengths are chosen",
        default=DEFAULTS.wavelength_sampling, items=[
        ("colour", "Color", "Importance by the color matching functions: least color noise"),
        ("visible", "Visible", "Importance by the eye's sensitivity (pbrt-v4's visible density)"),
        ("light", "Lights", "Importance by the lights' spectra"),
        ("uniform", "Uniform", "Every wavelength alike, from Min to Max (360–830 nm by default)"),
        ("d65_rejection", "D65", "Importance by daylight (rejection sampling)"),
        ("uv", "UV", "Uniform from 250 nm to Max, into the ultraviolet (the report's sampler; not needed for "
                "fluorescence, whose excitation wavelengths are drawn from the dye)")])
    wavelengths_per_path: bpy.props.EnumProperty(
        name="Wavelengths per Path", default=str(DEFAULTS.wavelengths_per_path),
        description="Wavelengths carried by each path",
        items=[("1", "1", "One wavelength per path"), ("4", "4 (Hero)", "A hero wavelength and three rotated ones")])
    lambda_min: bpy.props.FloatProperty(name="Min", description="Shortest rendered wavelength (nm)",
                                        default=DEFAULTS.lambda_min, min=LAMBDA_MIN, max=LAMBDA_MAX)
    lambda_max: bpy.props.FloatProperty(name="Max", description="Longest rendered wavelength (nm)",
                                        default=DEFAULTS.lambda_max, min=LAMBDA_MIN, max=LAMBDA_MAX)
    cmf: bpy.props.EnumProperty(name="Color Matching", description="Color matching functions: spectrum to XYZ",
                                default=DEFAULTS.cmf, items=[
        ("cie1931", "CIE 1931", "The exact CIE 1931 2° observer tables"),
        ("wyman1", "Wyman (single lobe)", "Wyman–Sloan–Shirley single-lobe fit"),
        ("wyman3", "Wyman (multi-lobe)", "Wyman–Sloan–Shirley multi-lobe fit")])
    spectral_exr: bpy.props.BoolProperty(
        name="Spectral EXR", default=DEFAULTS.spectrum,
        description="Also keep each pixel's spectrum and write it next to the render output (its path with "
                    "_spectral.exr for the extension): one channel per wavelength bin, the OpenEXR spectral layout "
                    "of Fichet et al. 2021. Not from a render farm or the Cycles emulation")
    spectral_exr_start: bpy.props.FloatProperty(name="Start", description="Where the first bin starts (nm)",
                                                default=DEFAULTS.spectrum_start, min=LAMBDA_MIN, max=LAMBDA_MAX)
    spectral_exr_end: bpy.props.FloatProperty(name="End", description="Where the last bin ends (nm)",
                                              default=DEFAULTS.spectrum_end, min=LAMBDA_MIN, max=LAMBDA_MAX)
    spectral_exr_step: bpy.props.FloatProperty(name="Step", description="The width of every bin (nm); it must "
                                               "divide End − Start", default=DEFAULTS.spectrum_step, min=0.1,
                                               max=LAMBDA_MAX - LAMBDA_MIN)
    device: bpy.props.EnumProperty(name="Device", description="Device to use for rendering", default="CPU", items=[
        ("CPU", "CPU", "Render on the CPU, with the backend chosen under Performance"),
        ("GPU", "GPU Compute", "Render on an NVIDIA GPU with CUDA (needs numba-cuda, which the extension does not "
         "bundle, and NVIDIA's driver; see the README)")])
    backend: bpy.props.EnumProperty(name="Backend", description="Which kernel traces the paths on the CPU",
                                    default=DEFAULTS.backend, items=[
        ("numba", "Numba", "Compiled kernel (fast)"),
        ("numpy", "NumPy", "Reference kernel without a compiler")])
    renderer: bpy.props.EnumProperty(name="Renderer", description="What renders the spectral scene",
                                     default="TRACER", items=[
        ("TRACER", "Tracer", "The spectral path tracer"),
        ("CYCLES", "Cycles Emulation", "Cycles, once per group of three wavelength bands, composited into XYZ "
         "(surfaces, area lights and Cycles features; no fluorescent re-emission). Render to Image or the "
         "command line, not F12")])
    emulation_band_mode: bpy.props.EnumProperty(name="Bands", default="AUTO", items=[
        ("AUTO", "Automatic", "As many bands as the scene's spectra need for an estimated color error below "
         f"ΔE00 {TARGET_DELTA_E:g}, narrow where the eye sees them change, within the render budget"),
        ("FIXED", "Fixed", "A given number of equal bands")],
        description="How the Cycles emulation splits the wavelength range into bands")
    emulation_max_renders: bpy.props.IntProperty(
        name="Max Renders", default=DEFAULT_MAX_RENDERS, min=1, soft_max=32,
        description="Most Cycles renders (each made twice, with two seeds) the automatic bands may use: "
                    "three bands per render, one where the anisotropy changes with wavelength")
    emulation_bands: bpy.props.IntProperty(
        name="Band Count", default=12, min=1, soft_max=48,
        description="Wavelength bands of the Cycles emulation: one Cycles render per three bands (per band "
                    "where the anisotropy changes with wavelength)")
    emulation_shader: bpy.props.EnumProperty(name="Shader", description="How the emulation shades its volumes",
                                             default="SVM", items=[
        ("SVM", "Nodes", "Plain Cycles nodes (faster)"),
        ("OSL", "OSL", "The Open Shading Language shader osl/spectral_volume.osl (CPU)")])
    scheduler_address: bpy.props.StringProperty(
        name="Scheduler", description="Dask scheduler to render on (tcp://host:port); empty: this computer")


class SpectralObjectSettings(bpy.types.PropertyGroup):
    """How an object becomes a medium: the density grid to read, or the voxel size for meshes."""

    density_grid: bpy.props.StringProperty(name="Density Grid", default="density",
                                           description="Grid of the VDB file (or fluid cache) used as density")
    voxel_size: bpy.props.FloatProperty(name="Voxel Size", description="Voxel size when a mesh is voxelised",
                                        default=0.05, min=1e-4, soft_max=1.0, subtype="DISTANCE", unit="LENGTH")


CLASSES = (SpectralRenderSettings, SpectralObjectSettings)
