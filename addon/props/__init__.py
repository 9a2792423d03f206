"""Settings the add-on stores in the .blend file: PropertyGroups and where they attach.

`scene.spectral` (render), `material.spectral` (volume material), `light.spectral` and
`world.spectral` (spectra), `object.spectral` (grid name, voxel size).
"""
