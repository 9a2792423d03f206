"""Operators of the add-on: export, render, Cycles emulation, presets, spectrum import."""
