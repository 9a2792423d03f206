"""The two backends of the path tracer: `numba_backend` (default) and `numpy_backend` (reference)."""
