"""Reads every part of a multi-part EXR (Blender writes one part per pass) into {channel: array}."""

import numpy as np


def read_all_parts(path) -> dict[str, np.ndarray]:
    import OpenImageIO as oiio

    image = oiio.ImageInput.open(str(path))
    assert image is not None, oiio.geterror()
    channels, part = {}, 0
    while image.seek_subimage(part, 0):
        pixels = image.read_image(part, 0, 0, image.spec().nchannels, "float")
        for i, name in enumerate(image.spec().channelnames):
            channels[name] = pixels[:, :, i]
        part += 1
    image.close()
    return channels
