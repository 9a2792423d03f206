"""Surface materials in the emulation: a temporary copy of each RGB material whose colours are upsampled to
spectra (`parameters.reflectance_bands`, or `emitter_bands` for emission colours) and given as their band
means in the render's R, G and B. Colours that other nodes compute (textures, ramps) cannot be upsampled
per pixel: they are rendered grey (their luminance, through an RGB to BW node) with a warning. A material
whose Spectral Surface is on has its reflectance spectrum's band means in every albedo input instead (what
the tracer renders: `export.surfaces`), its other colours upsampled as above.
"""

from ..nodes.surface import albedo_socket
from ..props.spectrum_values import to_spectrum
from . import parameters
from .bands import band_means
from .shaders import channels

EMISSIVE_SOCKETS = ("Emission Color",)
TEXTURED_WARNING = ("material {name!r}: colours computed by nodes (textures, ramps) are not spectral in the "
                    "Cycles emulation and render grey")


def _is_emissive(node, socket) -> bool:
    return node.type in ("EMISSION", "BACKGROUND") or socket.name in EMISSIVE_SOCKETS


def band_material(borrowed, material, members, bands, cmf: str, warnings: list):
    """A temporary copy of `material` with its colours in the bands `members`; without animation, which
    would put the RGB colours back when Cycles evaluates the frame (the values at this frame are the
    material's own)."""
    copy = borrowed.keep(material.copy())
    copy.animation_data_clear()
    tree = copy.node_tree
    if tree is None:
        return copy
    tree.animation_data_clear()
    spectral = material.spectral.use_surface
    albedo = channels(band_means(to_spectrum(material.spectral.reflectance).values, bands, cmf), members) \
        if spectral else None
    for node in list(tree.nodes):
        for socket in node.inputs:
            if socket.type != "RGBA" or not socket.enabled:
                continue
            if spectral and socket.name == albedo_socket(node):
                if socket.is_linked:
                    tree.links.remove(socket.links[0])
                socket.default_value = (*albedo, socket.default_value[3])
                continue
            if socket.is_linked:
                _grey(tree, socket)
                message = TEXTURED_WARNING.format(name=material.name)
                if message not in warnings:
                    warnings.append(message)
                continue
            upsample = parameters.emitter_bands if _is_emissive(node, socket) else parameters.reflectance_bands
            colour = socket.default_value
            socket.default_value = (*channels(upsample(colour[:3], bands, cmf), members), colour[3])
    return copy


def _grey(tree, socket) -> None:
    link = socket.links[0]
    grey = tree.nodes.new("ShaderNodeRGBToBW")
    tree.links.new(link.from_socket, grey.inputs["Color"])
    tree.links.new(grey.outputs["Val"], socket)
