"""Render settings (Properties editor ▸ Render) and per-object volume settings (▸ Object)."""

import functools
import textwrap

import bpy

from ..export.fluids import fluid_domain
from ..operators.emulation import ESTIMATES
from ..tracer import denoise
from ..tracer.kernels import cuda_target
from .panel import SpectralPanel


def draw_render_main(layout, scene) -> None:
    settings = scene.spectral
    layout.prop(settings, "renderer")
    if settings.renderer == "TRACER":
        draw_device(layout, settings)
    column = layout.column(align=True)
    row = column.row(heading="Noise Threshold", align=True)
    row.prop(settings, "use_adaptive_sampling", text="")
    threshold = row.row()
    threshold.active = settings.use_adaptive_sampling
    threshold.prop(settings, "adaptive_threshold", text="")
    column.prop(settings, "samples", text="Max Samples" if settings.use_adaptive_sampling else "Samples")
    minimum = column.row()
    minimum.active = settings.use_adaptive_sampling
    minimum.prop(settings, "adaptive_min_samples")
    column.prop(settings, "preview_samples", text="Viewport")
    layout.prop(settings, "max_bounces")
    layout.prop(settings, "seed")
    draw_denoise(layout, settings)
    if settings.renderer == "CYCLES":
        draw_emulation(layout.box(), scene)


@functools.cache
def gpu_problem():
    """Why the GPU cannot render here (None where it can), asked once per Blender session: the first ask imports
    numba-cuda and looks for the driver, which takes a moment."""
    return cuda_target.device_problem()


def draw_device(layout, settings) -> None:
    """The Device, with what stops the GPU from rendering where it cannot (the render would fail saying so)."""
    layout.prop(settings, "device")
    if settings.device == "GPU" and gpu_problem():
        column = layout.column(align=True)
        column.alert = True
        for number, line in enumerate(textwrap.wrap(gpu_problem(), 56)):
            column.label(text=line, icon="ERROR" if number == 0 else "BLANK1")


def draw_denoise(layout, settings) -> None:
    """The Denoise options, greyed out where Open Image Denoise cannot load."""
    heading = "Denoise" if denoise.available() else "Denoise (Open Image Denoise not available on this platform)"
    column = layout.column(align=True, heading=heading)
    column.enabled = denoise.available()
    column.prop(settings, "denoise", text="Render")
    column.prop(settings, "viewport_denoise", text="Viewport")


def draw_emulation(layout, scene) -> None:
    settings = scene.spectral
    layout.prop(settings, "emulation_band_mode")
    if settings.emulation_band_mode == "AUTO":
        layout.prop(settings, "emulation_max_renders")
        row = layout.row()
        row.operator("spectral.estimate_emulation_bands", icon="COLOR")
        estimate = ESTIMATES.get(scene.name)
        if estimate:
            layout.label(text=estimate, icon="INFO")
    else:
        layout.prop(settings, "emulation_bands")
    layout.prop(settings, "emulation_shader")
    layout.label(text="Render to Image or the command line (F12 renders nothing)", icon="INFO")
    layout.label(text="Fluorescence: absorption only, no re-emission (a dyed test cloud: ΔE00 20 from the tracer)",
                 icon="ERROR")
    layout.label(text="Surfaces: RGB colors upsampled; textures gray", icon="INFO")


def draw_wavelengths(layout, scene) -> None:
    settings = scene.spectral
    layout.prop(settings, "wavelength_sampling")
    layout.prop(settings, "wavelengths_per_path")
    column = layout.column(align=True)
    column.prop(settings, "lambda_min", text="Wavelength Min")
    column.prop(settings, "lambda_max", text="Max")
    layout.prop(settings, "bands")
    layout.prop(settings, "cmf")


def draw_object(layout, obj) -> None:
    settings = obj.spectral
    domain = obj.type == "MESH" and fluid_domain(obj) is not None
    if obj.type == "VOLUME" or domain:
        layout.prop(settings, "density_grid")
    if obj.type == "MESH" and not domain:
        layout.prop(settings, "voxel_size")


class RenderPanel(SpectralPanel):
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"


class SPECTRAL_PT_render(RenderPanel, bpy.types.Panel):
    bl_label = "Spectral Sampling"
    bl_idname = "SPECTRAL_PT_render"

    def draw_settings(self, layout, context):
        draw_render_main(layout, context.scene)


class SPECTRAL_PT_render_wavelengths(RenderPanel, bpy.types.Panel):
    bl_label = "Wavelengths"
    bl_idname = "SPECTRAL_PT_render_wavelengths"
    bl_parent_id = "SPECTRAL_PT_render"

    def draw_settings(self, layout, context):
        draw_wavelengths(layout, context.scene)


class SPECTRAL_PT_render_performance(RenderPanel, bpy.types.Panel):
    bl_label = "Performance"
    bl_idname = "SPECTRAL_PT_render_performance"
    bl_parent_id = "SPECTRAL_PT_render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_settings(self, layout, context):
        settings = context.scene.spectral
        backend = layout.row()
        backend.active = settings.device == "CPU"
        backend.prop(settings, "backend")
        layout.prop(settings, "scheduler_address")


class SPECTRAL_PT_render_clamping(RenderPanel, bpy.types.Panel):
    bl_label = "Clamping"
    bl_idname = "SPECTRAL_PT_render_clamping"
    bl_parent_id = "SPECTRAL_PT_render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_settings(self, layout, context):
        settings = context.scene.spectral
        column = layout.column(align=True)
        column.prop(settings, "clamp_direct")
        column.prop(settings, "clamp_indirect")
        row = layout.row(heading="Firefly Filter", align=True)
        row.prop(settings, "use_firefly_filter", text="")
        threshold = row.row()
        threshold.active = settings.use_firefly_filter
        threshold.prop(settings, "firefly_threshold", text="")


class SPECTRAL_PT_object(SpectralPanel, bpy.types.Panel):
    bl_label = "Spectral Volume"
    bl_idname = "SPECTRAL_PT_object"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        obj = getattr(context, "object", None)
        return super().poll(context) and obj is not None and obj.type in ("VOLUME", "MESH")

    def draw_settings(self, layout, context):
        draw_object(layout, context.object)


CLASSES = (SPECTRAL_PT_render, SPECTRAL_PT_render_wavelengths, SPECTRAL_PT_render_clamping,
           SPECTRAL_PT_render_performance, SPECTRAL_PT_object)
