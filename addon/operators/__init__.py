"""Operators of the add-on: export, render, Cycles emulation, presets, albedo levels, spectrum import."""
