"""Surface textures (issue 29 item 1): the export of a 1024² 8-bit sRGB Image Texture on a plane from Blender (as a
module: the add-on's exporter), its lowering, the kernel's bytes per texel, the RGB lattice's one-time fit, and the
colour round trip of texel spectra (random colours' reflectance under D65 back to RGB). Prints seconds and errors."""

import argparse
import time

import numpy as np

from addon.tracer import colorimetry, spectra, texel_spectra
from addon.tracer.kernels.lookups import on_grid
from addon.tracer.kernels.surfaces import rgb_reflectance
from addon.tracer.lowering import compile_scene
from addon.tracer.wavelengths import GRID


def round_trip(count: int, seed: int = 1) -> tuple[float, float, float]:
    """(largest |RGB error|, largest reflectance outside [0, 1], largest spread of a grey's spectrum) of `count`
    random colours and `count` random greys through the lattice's spectra, lit by D65 of luminance 1."""
    rng = np.random.default_rng(seed)
    colours = np.concatenate([rng.uniform(0.0, 1.0, (count, 3)), np.repeat(rng.uniform(0.0, 1.0, (count, 1)), 3, 1)])
    at = on_grid(np.broadcast_to(GRID, (colours.shape[0], GRID.size)))
    reflectance = rgb_reflectance(texel_spectra.lattice_spectra(), colours[:, 0:1], colours[:, 1:2], colours[:, 2:3],
                                  at)
    d65 = spectra.illuminant("D65").values
    white = colorimetry.spectrum_to_xyz(d65)[1]
    back = np.array([colorimetry.xyz_to_rgb(colorimetry.spectrum_to_xyz(r * d65) / white) for r in reflectance])
    outside = max(float(-reflectance.min()), float(reflectance.max() - 1.0), 0.0)
    return float(np.abs(back - colours).max()), outside, float(np.ptp(reflectance[count:], axis=1).max())


def export_seconds(size: int) -> tuple[float, object]:
    """Seconds of `export_scene` for a plane whose Diffuse BSDF's Color is a size² 8-bit sRGB image, and the scene."""
    import bpy

    import addon
    from addon.export.scene import export_scene

    bpy.ops.wm.read_factory_settings(use_empty=False)
    addon.register()
    bpy.context.scene.render.engine = "SPECTRAL_VOLUME"
    image = bpy.data.images.new("Big", size, size)
    image.pixels.foreach_set(np.random.default_rng(2).uniform(0.0, 1.0, size * size * 4).astype(np.float32))
    material = bpy.data.objects["Cube"].active_material
    tree = material.node_tree
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    tree.links.new(node.outputs["Color"], tree.nodes["Principled BSDF"].inputs["Base Color"])
    depsgraph = bpy.context.evaluated_depsgraph_get()
    start = time.perf_counter()
    export = export_scene(depsgraph)
    return time.perf_counter() - start, export.scene


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--size", type=int, default=1024, help="the image's width and height")
    parser.add_argument("--colours", type=int, default=2000, help="random colours (and greys) in the round trip")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    texel_spectra.lattice_spectra()
    print(f"RGB lattice ({texel_spectra.RGB_LATTICE}³ nodes) fitted in {time.perf_counter() - start:.2f} s, "
          f"{texel_spectra.lattice_spectra().nbytes / 2**20:.2f} MiB")
    error, outside, spread = round_trip(args.colours)
    print(f"round trip of {args.colours} colours under D65: largest |RGB error| {error:.2e}, reflectance outside "
          f"[0, 1] by {outside:.1e}, greys' largest spread {spread:.2e}")
    seconds, scene = export_seconds(args.size)
    texture = scene.surfaces[0].texture
    print(f"export of a {args.size}² 8-bit sRGB texture on the cube: {seconds:.2f} s "
          f"(image {texture.image.shape}, sRGB-encoded {texture.srgb})")
    start = time.perf_counter()
    kernel = compile_scene(scene)
    seconds = time.perf_counter() - start
    texels = kernel.surfaces.texels
    print(f"lowering: {seconds:.2f} s; the kernel keeps {texels.nbytes / texels.shape[0]:.0f} bytes per texel "
          f"({texels.nbytes / 2**20:.1f} MiB), the scene {texture.image.nbytes / texels.shape[0]:.0f}")


if __name__ == "__main__":
    main()
