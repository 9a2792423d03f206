"""Blender's shader node trees read as constants, with Cycles' meaning: volume shaders as spectra
(`volume`), what feeds a socket (`graph`), and what could not be read as set (`notes`). Below both the
settings (`props`, whose switches start from the node values) and the export."""
