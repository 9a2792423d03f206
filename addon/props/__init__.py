"""Settings the add-on stores in the .blend file: PropertyGroups and where they attach, and what a
setting means as data.

`scene.spectral` (render), `material.spectral` (volume material), `light.spectral` and
`world.spectral` (spectra), `object.spectral` (grid name, voxel size). A spectrum setting's tracer
Spectrum (`spectrum_values`), its swatch colour (`swatch`) and its curve widget (`curves`) live here
too, so the export, the panels and the operators read settings and nothing here reads them.
"""
