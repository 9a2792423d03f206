"""Drawing one spectrum setting: source, its parameters, curve widget, swatch and problems."""

from bpy.app.translations import pgettext_iface as iface_

from ..props import curves
from ..props.spectrum_values import problem
from ..operators.targets import point_at

LIGHT_PRESETS = "SPECTRAL_PT_light_presets"


def draw_spectrum(layout, settings, text: str, presets: bool = False) -> None:
    """Draw `settings` (a spectrum PropertyGroup) under the heading `text`."""
    column = layout.column()
    header = column.row(align=True)
    header.use_property_split = False
    header.label(text=text)
    if settings.ROLE:
        header.prop(settings, "preview", text="")
    header.prop(settings, "source", text="")
    if presets:
        header.context_pointer_set("spectral_spectrum", settings)  # what the presets apply to and save
        header.popover(panel=LIGHT_PRESETS, text="", icon="PRESET")
    _draw_source(column, settings)
    if settings.source != "CURVE":
        point_at(column.operator("spectral.spectrum_to_curve", icon="FCURVE"), settings)
    if hasattr(settings, "use_window"):
        column.prop(settings, "use_window", text="Wavelength Window")
        window = column.column(align=True)
        window.active = settings.use_window
        window.prop(settings, "window_min", text="Window Min")
        window.prop(settings, "window_max", text="Max")
    message = problem(settings)
    if message is not None:
        column.label(text=message, icon="ERROR")


def _draw_source(column, settings) -> None:
    source = settings.source
    if source == "CONSTANT":
        column.prop(settings, "value")
    elif source == "ILLUMINANT":
        column.prop(settings, "illuminant")
    elif source == "BLACKBODY":
        column.prop(settings, "temperature")
    elif source == "BAND":
        column.prop(settings, "band")
    elif source == "GAUSSIAN":
        peak = column.column(align=True)
        peak.prop(settings, "peak")
        peak.prop(settings, "width")
    elif source == "COLOR":
        column.prop(settings, "color")
        column.prop(settings, "rgb_method")
    elif source == "CURVE":
        _draw_curve(column, settings)
    elif source == "CSV":
        row = column.row(align=True)
        row.use_property_split = False
        row.prop(settings, "filepath", text="")
        point_at(row.operator("spectral.import_spectrum_csv", text="", icon="FILEBROWSER"), settings)
        column.prop(settings, "units")
    if source in ("BAND", "GAUSSIAN") and hasattr(settings, "value"):
        column.prop(settings, "value")


def _draw_curve(column, settings) -> None:
    node = curves.find_node(settings.curve)
    if node is None:
        column.label(text="The curve is missing", icon="ERROR")
        return
    if curves.is_shared(settings.id_data):
        row = column.row()
        row.label(text="Curves shared with a copy", icon="ERROR")
        point_at(row.operator("spectral.curves_single_user", text="Make Single-User"), settings)
    column.template_curve_mapping(node, "mapping")
    selected = curves.selected_points(node.mapping)
    if len(selected) == 1:
        (nm, value), = selected
        text = iface_("Selected: {:.1f} nm → {:.3g}   (x = nm ÷ {:g})").format(nm, value, curves.NM_PER_X)
        column.label(text=text, translate=False)
    else:
        column.label(text=iface_("x: wavelength ÷ {:g} nm (5.5 = 550 nm)").format(curves.NM_PER_X), translate=False)
