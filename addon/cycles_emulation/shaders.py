"""Volume materials of one Cycles render: a medium's coefficients in the render's (up to) three bands, as
plain Cycles nodes (SVM, the default and faster) or as the OSL shader `osl/spectral_volume.osl`.

Both compute, per channel c (band k), from the raw density ρ (the object's density grid, or 1 inside a
mesh as the tracer voxelises it): σ_t = ρ · s · ext_k, albedo_k(ρ) linear between the density levels and
clamped outside, σ_s = σ_t · albedo, σ_a = σ_t − σ_s + ρ · s · excitation_k; phase Henyey–Greenstein g
(equal in the packed bands) or Rayleigh. SVM: Map Range and Vector Math nodes into a Volume Coefficients
node, which also takes blackbody emission (σ_t − σ_s) · intensity · Planck_k(T), Planck's band means
tabulated over the temperature grid's range (the OSL shader has no emission). OSL: a script node compiled by
Blender (`cycles.osl`; needs CPU and Open Shading Language on). Cycles' OSL reads volume grids stochastically
(one voxel, picked by the trilinear weights), so the shader reads the grid a second time for the albedo
(`AlbedoGrid`, Cycles' name `geom:<grid>`): with two independent picks σ_s is exact wherever the neighbouring
voxels lie on one linear piece of the albedo table (osl/spectral_volume.osl).
"""

from pathlib import Path

import bpy
import numpy as np

from ..tracer.errors import SpectralError
from .parameters import MediumBands

def _load_osl_query() -> None:
    """Blender's OSL query module returns Blender's own OpenImageIO types; where another OpenImageIO is
    installed (pip's, which colour-science imports), whichever loads first owns them, so load Blender's
    as soon as the add-on does. In Blender-as-a-module it is importable after `expose_bundled_modules`."""
    expose = getattr(bpy.utils, "expose_bundled_modules", None)
    if expose is not None:
        expose()
    try:
        import oslquery  # noqa: F401
    except ImportError:
        pass  # reported when an OSL shader is compiled


_load_osl_query()
SHADERS = ("SVM", "OSL")
OSL_SOURCE = Path(__file__).resolve().parents[2] / "osl" / "spectral_volume.osl"
OSL_LEVELS = 8  # density levels the OSL shader takes (Density0…7, Albedo0…7)


def channels(values, members) -> tuple[float, float, float]:
    """Band values of a render's members as R, G, B (unused channels 0)."""
    out = [0.0, 0.0, 0.0]
    for channel, band in enumerate(members):
        out[channel] = float(values[band])
    return tuple(out)


def _density(nodes, attribute: str | None):
    if attribute is None:
        value = nodes.new("ShaderNodeValue")
        value.outputs[0].default_value = 1.0
        return value.outputs[0]
    node = nodes.new("ShaderNodeAttribute")
    node.attribute_name = attribute
    return node.outputs["Fac"]


def _vector_math(tree, operation: str, *inputs):
    """A Vector Math node; each input is a socket (linked) or a value (set)."""
    node = tree.nodes.new("ShaderNodeVectorMath")
    node.operation = operation
    slots = [node.inputs["Scale"]] if operation == "SCALE" else []
    for socket, value in zip([s for s in node.inputs if s.enabled and s.name != "Scale"] + slots, inputs):
        if isinstance(value, bpy.types.NodeSocket):
            tree.links.new(value, socket)
        else:
            socket.default_value = value
    return node.outputs["Vector"]


def _svm_table(tree, x, xs, rows, members):
    """Rows (N, K) tabulated at increasing xs, linear in x between them and clamped outside, as a vector."""
    result = channels(rows[0], members)
    for i in range(len(xs) - 1):
        ramp = tree.nodes.new("ShaderNodeMapRange")
        ramp.clamp = True
        tree.links.new(x, ramp.inputs["Value"])
        ramp.inputs["From Min"].default_value, ramp.inputs["From Max"].default_value = xs[i], xs[i + 1]
        step = channels(rows[i + 1] - rows[i], members)
        result = _vector_math(tree, "MULTIPLY_ADD", step, ramp.outputs["Result"], result)
    return result


def _svm_thermal(tree, plain_absorption, thermal, temperature_attribute: str, members):
    """σ_a · intensity · Planck(T) per band, T from the temperature grid."""
    grid = tree.nodes.new("ShaderNodeAttribute")
    grid.attribute_name = temperature_attribute
    kelvin = tree.nodes.new("ShaderNodeMath")
    kelvin.operation = "MULTIPLY_ADD"
    tree.links.new(grid.outputs["Fac"], kelvin.inputs[0])
    kelvin.inputs[1].default_value, kelvin.inputs[2].default_value = thermal.scale, thermal.offset
    radiance = _svm_table(tree, kelvin.outputs["Value"], thermal.temperatures, thermal.radiance, members)
    return _vector_math(tree, "SCALE", _vector_math(tree, "MULTIPLY", plain_absorption, radiance), thermal.intensity)


def _svm(tree, density, medium: MediumBands, members, g: float, temperature_attribute: str | None):
    scale = medium.density_scale
    sigma_t = _vector_math(tree, "SCALE", channels(medium.extinction * scale, members), density)
    albedo = _svm_table(tree, density, medium.albedo_densities, medium.albedo, members)
    scattering = _vector_math(tree, "MULTIPLY", sigma_t, albedo)
    plain_absorption = _vector_math(tree, "SUBTRACT", sigma_t, scattering)
    absorption = _vector_math(tree, "MULTIPLY_ADD", channels(medium.excitation * scale, members), density,
                              plain_absorption)
    node = tree.nodes.new("ShaderNodeVolumeCoefficients")
    if medium.thermal is not None:
        tree.links.new(_svm_thermal(tree, plain_absorption, medium.thermal, temperature_attribute, members),
                       node.inputs["Emission Coefficients"])
    if medium.phase == "rayleigh":
        node.phase = "RAYLEIGH"  # no Anisotropy input then
    else:
        node.phase = "HENYEY_GREENSTEIN"
        node.inputs["Anisotropy"].default_value = g
    tree.links.new(scattering, node.inputs["Scatter Coefficients"])
    tree.links.new(absorption, node.inputs["Absorption Coefficients"])
    return node.outputs["Volume"]


def osl_text(borrowed):
    """The OSL source as a temporary Text datablock (script nodes compile Text or file sources)."""
    text = borrowed.keep(bpy.data.texts.new(".spectral_volume.osl"))
    text.from_string(OSL_SOURCE.read_text(encoding="utf-8"))
    return text


def _compile(node, text) -> None:
    from cycles import osl

    messages = []
    node.mode, node.script = "INTERNAL", text
    if not osl.update_script_node(node, lambda kind, message: messages.append(message)) or not node.bytecode:
        raise SpectralError(f"the OSL shader {OSL_SOURCE.name} did not compile: {'; '.join(messages)}")


def _osl(tree, density, medium: MediumBands, members, g: float, _temperature_attribute, text, attribute):
    if medium.thermal is not None:
        raise SpectralError(f"material of {medium.name!r} glows by temperature: the OSL shader has no blackbody "
                            "emission, use the Nodes (SVM) shader")
    if len(medium.albedo_densities) > OSL_LEVELS:
        raise SpectralError(f"material of {medium.name!r} has {len(medium.albedo_densities)} albedo levels; the OSL "
                            f"shader takes at most {OSL_LEVELS}: use the Nodes (SVM) shader")
    node = tree.nodes.new("ShaderNodeScript")
    _compile(node, text)
    tree.links.new(density, node.inputs["Density"])
    values = {"DensityScale": medium.density_scale, "Extinction": (*channels(medium.extinction, members), 1.0),
              "Excitation": (*channels(medium.excitation, members), 1.0), "Anisotropy": g,
              "Rayleigh": int(medium.phase == "rayleigh"), "LevelCount": len(medium.albedo_densities),
              "AlbedoGrid": f"geom:{attribute}" if attribute else ""}
    for i, level in enumerate(medium.albedo_densities):
        values[f"Density{i}"] = float(level)
        values[f"Albedo{i}"] = (*channels(medium.albedo[i], members), 1.0)
    for name, value in values.items():
        node.inputs[name].default_value = value
    return node.outputs["Volume"]


def volume_material(borrowed, medium: MediumBands, members, attribute: str | None, shader: str = "SVM", text=None,
                    temperature: str | None = None):
    """A temporary material holding `medium` in the bands `members` (R, G, B); `attribute` names the density
    grid (None: density 1, for meshes), `temperature` the temperature grid of a glowing medium. OSL needs
    `text` from `osl_text`."""
    if shader not in SHADERS:
        raise SpectralError(f"unknown emulation shader {shader!r}; choose one of {', '.join(SHADERS)}")
    material = borrowed.keep(bpy.data.materials.new(f".spectral emulation {medium.name}"))
    tree = material.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    density = _density(tree.nodes, attribute)
    g = float(np.mean([medium.anisotropy[band] for band in members]))
    build = _svm if shader == "SVM" else lambda *args: _osl(*args, text, attribute)
    tree.links.new(build(tree, density, medium, members, g, temperature), output.inputs["Volume"])
    return material
