import bpy
# Spectral Volume light spectrum preset: it sets every setting listed here
spectrum = bpy.context.spectral_spectrum

spectrum.source = 'BLACKBODY'
spectrum.illuminant = 'D65'
spectrum.temperature = 1900.0
spectrum.band = 'UV365'
spectrum.peak = 520.0
spectrum.width = 20.0
spectrum.color = (0.8, 0.8, 0.8)
spectrum.rgb_method = 'jakob2019'
spectrum.filepath = ''
spectrum.units = 'nm'
