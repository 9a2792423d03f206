"""The kernels: the two backends of the path tracer, `numba_backend` (default) and `numpy_backend` (the
reference), the shared arithmetic both run (`lookups`, `geometry`, `media`, `light_sampling`, `envmap`, `dda`,
`rng`, `fluorescent_reservoir`), the data they read (`layout`) and the compiled kernel's cache (`numba_cache`);
docs/architecture.md, "The kernel"."""
