"""Marks functions as shared math: plain NumPy-compatible code that the NumPy backend calls on arrays
and that Numba kernels compile in place (`numba.extending.register_jitable`).

Without Numba installed the decorator changes nothing, so the NumPy backend needs no compiler.
"""

try:
    from numba.extending import register_jitable as shared
except ImportError:  # the NumPy backend works without Numba

    def shared(function):
        return function
