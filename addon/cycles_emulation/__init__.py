"""Cycles spectral emulation: the scene rendered by Cycles once per group of wavelength bands (three bands
share a render through its R, G and B channels) and the renders composited into XYZ.

Pure modules (no `bpy`): `bands` (band edges, XYZ weights, band means, packing), `band_plan` (how many bands
and where, from an estimate of their colour error), `parameters` (per-band numbers of a tracer Scene),
`composite` (renders → XYZ film). Blender modules: `shaders` (volume node
trees, SVM or OSL), `surfaces` (RGB materials upsampled per band), `setup` (one render's settings, lights,
World and materials), `fluids` (Volume objects standing in for fluid domains), `state` (temporary changes
undone), `job` (the driver: the emulation's render job, addon/jobs/).
"""
