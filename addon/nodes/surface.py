"""Surface shaders, as far as the export needs them while surfaces are not rendered: whether a material's
surface emits light (an Emission node, or a Principled BSDF with Emission Strength and a non-black Emission
Color), which makes its mesh a light that the render report must name."""

from .graph import output_source, source

_EMISSIVE = {"ShaderNodeEmission": ("Strength", "Color"), "ShaderNodeBsdfPrincipled": ("Emission Strength",
                                                                                        "Emission Color")}


def _emits(node, seen) -> bool:
    if node.as_pointer() in seen:
        return False
    seen.add(node.as_pointer())
    if node.bl_idname in _EMISSIVE:
        strength, colour = (node.inputs[name] for name in _EMISSIVE[node.bl_idname])
        bright = strength.is_linked or strength.default_value > 0
        coloured = colour.is_linked or any(value > 0 for value in colour.default_value[:3])
        return bright and coloured
    return any(_emits(found[0], seen) for socket in node.inputs if socket.type == "SHADER"
               for found in [source(socket)] if found is not None)


def emits_light(material) -> bool:
    found = None if material is None else output_source(material.node_tree, "Surface")
    return found is not None and _emits(found[0], set())
