"""A View Layer's render passes → the tracer's data and light passes (`tracer/passes.py`, `tracer/light_passes.py`),
and the passes it asks for that the engine does not make, named for the render report's warning; the Render
settings' Spectral EXR → the tracer's spectral image (`tracer/spectral_film.py`).

The engine makes Combined, XYZ and XYZ Variance always, and the View Layer's Z (Depth), Mist, Normal and
Cryptomatte Object and Material (at its Cryptomatte Levels), the Mist pass after the World's Mist Pass settings, and
its light passes Emission, Environment, Volume Direct and Volume Indirect (Cycles' toggles of the last two).
"""

import dataclasses

from ..tracer.light_passes import EMIT, ENV, VOLUME_DIR, VOLUME_IND
from ..tracer.passes import CRYPTO_MATERIAL, CRYPTO_OBJECT, DATA_PASSES, DEPTH, MIST, NORMAL

# The View Layer's toggle of each data pass the engine makes.
TOGGLES = {DEPTH: "use_pass_z", MIST: "use_pass_mist", NORMAL: "use_pass_normal",
           CRYPTO_OBJECT: "use_pass_cryptomatte_object", CRYPTO_MATERIAL: "use_pass_cryptomatte_material"}
# The View Layer's toggle of each light pass the engine makes: (owner of the toggle, toggle), the owner "" for the
# View Layer itself, "cycles" for Cycles' settings of it (where Blender keeps the volume passes' toggles).
LIGHT_TOGGLES = {EMIT: ("", "use_pass_emit"), ENV: ("", "use_pass_environment"),
                 VOLUME_DIR: ("cycles", "use_pass_volume_direct"), VOLUME_IND: ("cycles", "use_pass_volume_indirect")}
# The passes Blender offers that the engine does not make: (owner of the toggle, toggle, name in the report).
UNMADE = (
    ("", "use_pass_position", "Position"), ("", "use_pass_vector", "Vector"), ("", "use_pass_uv", "UV"),
    ("", "use_pass_object_index", "Object Index"), ("", "use_pass_material_index", "Material Index"),
    ("", "use_pass_diffuse_direct", "Diffuse Direct"), ("", "use_pass_diffuse_indirect", "Diffuse Indirect"),
    ("", "use_pass_diffuse_color", "Diffuse Color"), ("", "use_pass_glossy_direct", "Glossy Direct"),
    ("", "use_pass_glossy_indirect", "Glossy Indirect"), ("", "use_pass_glossy_color", "Glossy Color"),
    ("", "use_pass_transmission_direct", "Transmission Direct"),
    ("", "use_pass_transmission_indirect", "Transmission Indirect"),
    ("", "use_pass_transmission_color", "Transmission Color"), ("", "use_pass_subsurface_direct", "Subsurface Direct"),
    ("", "use_pass_subsurface_indirect", "Subsurface Indirect"), ("", "use_pass_subsurface_color", "Subsurface Color"),
    ("", "use_pass_ambient_occlusion", "Ambient Occlusion"), ("", "use_pass_shadow", "Shadow"),
    ("", "use_pass_cryptomatte_asset", "Cryptomatte Asset"), ("", "use_pass_grease_pencil", "Grease Pencil"),
    ("eevee", "use_pass_volume_direct", "Volume Light"), ("eevee", "use_pass_transparent", "Transparent"),
    ("cycles", "denoising_store_passes", "Denoising Data"), ("cycles", "pass_debug_sample_count", "Sample Count"),
    ("cycles", "use_pass_shadow_catcher", "Shadow Catcher"),
)
FALLOFFS = {"QUADRATIC": "quadratic", "LINEAR": "linear", "INVERSE_QUADRATIC": "inverse_quadratic"}


def pass_settings(view_layer, world) -> dict:
    """The RenderSettings fields of the View Layer's data passes (`passes`, `mist_*`, `cryptomatte_depth`);
    Mist's settings from the World (Blender's defaults without one)."""
    light = tuple(name for name, (owner, toggle) in LIGHT_TOGGLES.items() if _toggled(view_layer, owner, toggle))
    fields = {"passes": tuple(name for name, toggle in TOGGLES.items() if getattr(view_layer, toggle)) + light,
              "cryptomatte_depth": int(view_layer.pass_cryptomatte_depth)}
    if world is not None:
        mist = world.mist_settings
        fields.update(mist_start=float(mist.start), mist_depth=float(mist.depth), mist_falloff=FALLOFFS[mist.falloff])
    return fields


def spectrum_settings(scene) -> dict:
    """The RenderSettings fields of the scene's Spectral EXR (`spectrum`, its bins)."""
    s = scene.spectral
    return {"spectrum": bool(s.spectral_exr), "spectrum_start": float(s.spectral_exr_start),
            "spectrum_end": float(s.spectral_exr_end), "spectrum_step": float(s.spectral_exr_step)}


def _toggled(view_layer, owner: str, toggle: str) -> bool:
    """Whether the View Layer's `toggle` (of its settings `owner`, "" for itself) is on; off where it has none."""
    settings = getattr(view_layer, owner, None) if owner else view_layer
    return settings is not None and bool(getattr(settings, toggle, False))


def unmade_passes(view_layer) -> list[str]:
    """The passes the View Layer asks for that the engine does not make (its AOVs and Light Groups included)."""
    names = [name for owner, toggle, name in UNMADE if _toggled(view_layer, owner, toggle)]
    names += [f"AOV {aov.name!r}" for aov in view_layer.aovs]
    names += [f"Light Group {group.name!r}" for group in view_layer.lightgroups]
    return names


def unmade_warning(view_layer) -> str | None:
    """The render report's warning naming the passes of the View Layer the engine leaves out, or None."""
    names = unmade_passes(view_layer)
    if not names:
        return None
    return (f"view layer {view_layer.name!r}: the passes {', '.join(names)} are not rendered by this engine (it makes "
            "Combined, XYZ, XYZ Variance, Z, Mist, Normal, Cryptomatte Object and Material, Emission, Environment, Volume "
            "Direct and Volume Indirect)")


def without_light_passes(export, renderer: str):
    """`export` (an `Export`) for a renderer that makes the data passes (from the camera rays' first hits,
    `tracer.render.first_hit_passes`) but no light passes and no spectral image (the Cycles
    emulation): its scene asks for none of those, and a warning names those left out."""
    settings = export.scene.settings
    light = tuple(name for name in settings.passes if name not in DATA_PASSES)
    if not light and not settings.spectrum:
        return export
    kept = tuple(name for name in settings.passes if name in DATA_PASSES)
    settings = dataclasses.replace(settings, passes=kept, spectrum=False)
    warnings = []
    if light:
        warnings.append(f"{renderer} does not render light passes yet: {', '.join(light)} left out of the render")
    if export.scene.settings.spectrum:
        warnings.append(f"{renderer} does not make the spectral image yet: no Spectral EXR written")
    return dataclasses.replace(export, scene=dataclasses.replace(export.scene, settings=settings),
                               warnings=[*export.warnings, *warnings])
