"""Benchmarks of the spectral tracer: scripts that print figures (see bench/README.md), never tests."""
