"""A quick Cycles still for the tests that look at what a render shows."""

import bpy
import numpy as np


def cycles_pixels(scene, path, size):
    """Renders `scene` with Cycles (4 samples, no denoising: Debian's Blender has no
    OpenImageDenoise) at size x size into `path` (kept as the test's artefact) and returns
    its pixels as an (N, 4) float array."""
    scene.render.engine = 'CYCLES'
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = size, size
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(str(path))
    pixels = np.empty(len(image.pixels), dtype=np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(-1, 4)
