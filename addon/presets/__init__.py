"""Light-spectrum and volume-material presets as Blender presets: what a preset stores, and writing one.

A preset is a Python file that Blender's `script.execute_preset` runs, as Cycles' sampling presets. It sets
every setting it stores, so applying it gives the same look whatever was there before: every setting of a
light spectrum or of a material (its spectra and albedo levels too) except those in `NOT_STORED`, the curve
storage (a curve's points are stored, through `set_curve_points`), the albedo level selected in the list,
and a light's wavelength window, a filter in front of the lamp rather than part of its spectrum's shape,
which a preset leaves as it was.

The built-in presets ship in this folder (`<subdir>/*.py`, made visible to Blender with
`bpy.utils.register_preset_path`); users' own go to their scripts folder (`scripts/presets/<subdir>`),
where Blender's Add Preset writes them and from where they can be shared.
"""

from pathlib import Path

from ..props import curves

BUILT_IN = Path(__file__).parent  # <subdir>/*.py: the built-in preset files
SEARCH_PATH = BUILT_IN.parent  # for bpy.utils.register_preset_path, which looks in its presets/<subdir>
LIGHT_SUBDIR = "spectral_volume/light_spectrum"
MATERIAL_SUBDIR = "spectral_volume/material"

NOT_STORED = {"rna_type", "name", "curve_group", "curve", "albedo_index", "use_window", "window_min", "window_max"}


def _stored(settings):
    """The properties of `settings` a preset stores, a spectrum's source first (read-only values, such as
    a swatch, are computed)."""
    stored = [prop for prop in settings.bl_rna.properties if prop.identifier not in NOT_STORED
              and (prop.type in ("POINTER", "COLLECTION") or not prop.is_readonly)]
    return sorted(stored, key=lambda prop: prop.identifier != "source")


def _number(value):
    """A float as short as it reads back the same in single precision (Blender's floats)."""
    return float(f"{value:.7g}") if isinstance(value, float) else value


def _assignments(settings, path: str, depth: int = 0):
    """Python lines that give `settings` (named `path` in them) its current values."""
    for prop in _stored(settings):
        name, value = prop.identifier, getattr(settings, prop.identifier)
        if prop.type == "POINTER":
            yield from _assignments(value, f"{path}.{name}", depth)
        elif prop.type == "COLLECTION":
            item = f"item_{depth}"
            yield f"{path}.{name}.clear()"
            for element in value:
                yield f"{item} = {path}.{name}.add()"
                yield from _assignments(element, item, depth + 1)
        else:
            value = tuple(map(_number, value)) if getattr(prop, "is_array", False) else _number(value)
            yield f"{path}.{name} = {value!r}"
    if getattr(settings, "source", None) == "CURVE":
        mapping = curves.find_mapping(settings.curve)
        if mapping is not None:
            points = tuple((round(nm, 3), _number(value)) for nm, value in curves.points(mapping))
            yield f"{path}.set_curve_points({points!r})"


def write(filepath, settings, define: str, note: str) -> None:
    """Write `settings` as a preset file. `define` binds a name to the settings the preset applies to
    (`spectrum = bpy.context.spectral_spectrum`); `note` is the file's opening comment."""
    name = define.split("=")[0].strip()
    lines = ["import bpy", f"# {note}", define, "", *_assignments(settings, name)]
    Path(filepath).write_text("\n".join(lines) + "\n", encoding="utf-8")
