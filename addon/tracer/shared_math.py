"""Marks functions as shared math: plain NumPy-compatible code that the NumPy backend calls on arrays
and that Numba kernels compile in place (`numba.extending.register_jitable`).

`shared` compiles a function of its own, which LLVM inlines into its caller or calls. `shared_inline` has
Numba inline the function's code into each caller before typing, as the kernel's `jit(inline="always")`
helpers are: for the trilinear look-up of the innermost loop, the lights and the DDA, which LLVM would call.
Numba's InlineInlinables pass inlines any global with `targetoptions` {"inline": "always"} and a `py_func`
(what a dispatcher has), so the plain function gets both; it stays registered as jitable for any call
the pass does not reach.

`select(condition, a, b)` chooses on a path's values where a product with a mask cannot (an operand that
may be infinite or NaN, an integer result): NumPy's `where` on arrays, a plain conditional on a Numba
kernel's scalars (where `np.where` would make a 0-d array).

Without Numba installed the decorators change nothing, so the NumPy backend needs no compiler.
"""

import numpy as np


def select(condition, if_true, if_false):
    """`if_true` where `condition` holds, else `if_false` (both are evaluated)."""
    return np.where(condition, if_true, if_false)


try:
    from numba import types
    from numba.extending import overload, register_jitable as shared
except ImportError:  # the NumPy backend works without Numba

    def shared(function):
        return function

    shared_inline = shared
else:

    @overload(select)
    def _select_in_kernels(condition, if_true, if_false):
        if all(isinstance(value, (types.Boolean, types.Number)) for value in (condition, if_true, if_false)):
            return lambda condition, if_true, if_false: if_true if condition else if_false
        return lambda condition, if_true, if_false: np.where(condition, if_true, if_false)

    def shared_inline(function):
        shared(function)
        function.targetoptions = {"inline": "always"}
        function.py_func = function
        return function
