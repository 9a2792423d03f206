"""The .blend command line: `python -m addon.cli render …` and `blender -c spectral_render …` (`command`), with
its frame and size options read as Blender's own command line reads them (`frame_options`)."""
