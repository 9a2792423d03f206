"""Light and World panels (Properties editor ▸ Light data, World) and the drawing the sidebar shares."""

import bpy
from bpy.app.translations import pgettext_iface as iface_

from .panel import SpectralPanel
from .spectrum import draw_spectrum

SUPPORTED_LIGHTS = ("SUN", "POINT", "SPOT", "AREA")


def draw_light(layout, light) -> None:
    """Brightness, size (the sun's Angle softens its shadows; an area light's shape, size and spread; the
    tracer's point and spot lights are points, so their Radius is greyed out and says why), then the colour: Blender's Color and
    Temperature, or with Spectral Light on, the spectrum and its unit."""
    if light.type not in SUPPORTED_LIGHTS:
        layout.label(text=iface_("{} lights are not rendered yet (sun, point, spot and area are)").format(
            iface_(light.bl_rna.properties["type"].enum_items[light.type].name)), translate=False, icon="ERROR")
        return
    column = layout.column()
    column.prop(light, "energy", text="Strength" if light.type == "SUN" else "Power")
    if light.type == "SUN":
        column.prop(light, "angle")
    elif light.type == "AREA":
        column.prop(light, "shape")
        if light.shape in ("SQUARE", "DISK"):
            column.prop(light, "size")
        else:
            column.prop(light, "size", text="Size X")
            column.prop(light, "size_y", text="Y")
        column.prop(light, "spread")
    else:
        radius = column.column()
        radius.active = False
        radius.prop(light, "shadow_soft_size", text="Radius")
        radius.label(text="The tracer renders a point: only the Cycles emulation uses the Radius", icon="INFO")
    column.prop(light.spectral, "enabled")
    if not light.spectral.enabled:
        column.prop(light, "color")
        row = column.row(heading="Temperature")
        row.prop(light, "use_temperature", text="")
        sub = row.row()
        sub.active = light.use_temperature
        sub.prop(light, "temperature", text="")
        return
    column.prop(light.spectral, "unit")
    draw_spectrum(layout, light.spectral.spectrum, "Spectrum", presets=True)


def draw_world(layout, world) -> None:
    settings = world.spectral
    layout.active = settings.enabled
    layout.prop(settings, "kind")
    layout.prop(settings, "strength")
    layout.prop(settings, "unit")
    draw_spectrum(layout, settings.spectrum, "Zenith" if settings.kind == "sky" else "Spectrum", presets=True)
    if settings.kind == "sky":
        draw_spectrum(layout, settings.horizon, "Horizon", presets=True)


class SPECTRAL_PT_light(SpectralPanel, bpy.types.Panel):
    bl_label = "Spectral Light"
    bl_idname = "SPECTRAL_PT_light"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and getattr(context, "light", None) is not None

    def draw_settings(self, layout, context):
        draw_light(layout, context.light)


class SPECTRAL_PT_world(SpectralPanel, bpy.types.Panel):
    bl_label = "Spectral World"
    bl_idname = "SPECTRAL_PT_world"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "world"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and getattr(context, "world", None) is not None

    def draw_header(self, context):
        self.layout.prop(context.world.spectral, "enabled", text="")

    def draw_settings(self, layout, context):
        draw_world(layout, context.world)


CLASSES = (SPECTRAL_PT_light, SPECTRAL_PT_world)
