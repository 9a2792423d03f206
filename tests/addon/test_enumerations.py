"""Each enumeration the add-on offers in Blender lists exactly the choices of the tracer's one definition of
it (docs/architecture.md, "Data flow": the scene format's enumerations live in `tracer/scene.py`,
`tracer/kernels/layout.py`, `tracer/colorimetry.py`, `tracer/spectra.py` and `tracer/backends.py`), with the tracer's default, so
a choice added to or removed from one side fails here instead of being refused at render time (or never
offered). Read from Blender's registered RNA, as a user sees the menus."""

import pytest

from addon.export.scene import render_settings
from addon.props.render import GPU_BACKEND
from addon.tracer import backends, colorimetry, scene as tracer_scene, spectra
from addon.tracer.kernels import layout
from addon.tracer.scene import RenderSettings
from addon.tracer.validation import check_settings

bpy = pytest.importorskip("bpy")

# (settings class, property, the tracer's choices as Blender's identifiers, whether Blender offers them all)
ENUMERATIONS = [
    ("SpectralRenderSettings", "wavelength_sampling", tracer_scene.WAVELENGTH_SAMPLINGS, True),
    ("SpectralRenderSettings", "cmf", colorimetry.CMF_NAMES, True),
    ("SpectralRenderSettings", "backend", tuple(name for name in backends.NAMES if name != GPU_BACKEND), True),
    ("SpectralRenderSettings", "wavelengths_per_path", tuple(map(str, layout.WAVELENGTHS_PER_PATH)), True),
    ("SpectralMaterialSettings", "phase", layout.PHASES, True),
    ("SpectralLightSettings", "unit", tracer_scene.LIGHT_UNITS, True),
    ("SpectralWorldSettings", "unit", tracer_scene.LIGHT_UNITS, True),
    ("SpectralWorldSettings", "kind", layout.LIGHT_KINDS, False),  # a World is an environment or a sky
    ("SpectralLightSpectrum", "illuminant", spectra.ILLUMINANT_NAMES, True),
    ("SpectralLightSpectrum", "band", tuple(spectra.BANDS), True),
    ("SpectralLightSpectrum", "rgb_method", tuple(spectra.RGB_METHODS), True),
    ("SpectralLightSpectrum", "units", tuple(spectra.CSV_UNITS), False),  # µm spelt one way, not three
]


def enum_property(type_name: str, name: str):
    from addon.props import light, material, render, spectrum

    owner = next(getattr(module, type_name) for module in (render, material, light, spectrum)
                 if hasattr(module, type_name))
    return owner.bl_rna.properties[name]


@pytest.mark.parametrize("type_name, name, tracer_choices, all_offered", ENUMERATIONS,
                         ids=[f"{t}.{n}" for t, n, _c, _a in ENUMERATIONS])
def test_blender_offers_the_tracers_choices(registered, type_name, name, tracer_choices, all_offered):
    offered = [item.identifier for item in enum_property(type_name, name).enum_items]
    assert len(offered) == len(set(offered))
    assert set(offered) <= set(tracer_choices), "Blender offers a choice the tracer does not know"
    if all_offered:
        assert set(offered) == set(tracer_choices), "the tracer has a choice Blender does not offer"


@pytest.mark.parametrize("name", ["wavelength_sampling", "cmf", "backend", "wavelengths_per_path"])
def test_render_enumerations_default_to_the_tracers_defaults_and_export_as_set(registered, name):
    """The Render settings' default is RenderSettings' own, and every choice set in Blender reaches the
    tracer's settings as that value and passes their check."""
    prop = enum_property("SpectralRenderSettings", name)
    assert prop.default == str(getattr(RenderSettings(), name))
    scene = bpy.context.scene
    for item in prop.enum_items:
        setattr(scene.spectral, name, item.identifier)
        settings = render_settings(scene)
        assert str(getattr(settings, name)) == item.identifier
        check_settings(settings)
