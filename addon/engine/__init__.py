"""The "Spectral Volume" render engine and its parts: F12 and `bpy.ops.render.render` (`render_engine`), the
Rendered viewport (`viewport_render` renders, `viewport_draw` draws), material, light and World thumbnails
(`thumbnails`), and the kernel's warm-up when a scene switches to the engine (`kernel_warmup`)."""
