"""Draws the Rendered viewport's image with Blender's `gpu` module: one float texture, made again only when
the image changes, drawn over the view's region (scaled when the view was resized since it rendered)."""

import gpu
from gpu_extras.presets import draw_texture_2d


class ViewportImage:
    def __init__(self):
        self.texture = None
        self.shown = None  # the pixel array the texture holds

    def draw(self, pixels, width: int, height: int) -> None:
        """Draw `pixels` ((rows, columns, 4) float32 RGBA, bottom row first) over width × height pixels of
        the bound framebuffer, from its lower-left corner, under whatever shader state the caller set up
        (the engine binds the display space shader)."""
        if pixels is not self.shown:
            rows, columns = pixels.shape[:2]
            data = gpu.types.Buffer("FLOAT", rows * columns * 4, pixels.ravel())
            self.texture = gpu.types.GPUTexture((columns, rows), format="RGBA16F", data=data)
            self.shown = pixels
        draw_texture_2d(self.texture, (0, 0), width, height)
