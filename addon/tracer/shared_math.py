"""Marks functions as shared math: plain NumPy-compatible code that the NumPy backend calls on arrays
and that Numba kernels compile in place (`numba.extending.register_jitable`).

`shared` compiles a function of its own, which LLVM inlines into its caller or calls. `shared_inline` has
Numba inline the function's code into each caller before typing, as the kernel's `jit(inline="always")`
helpers are: for the trilinear look-up of the innermost loop, the lights and the DDA, which LLVM would call.
Numba's InlineInlinables pass inlines any global with `targetoptions` {"inline": "always"} and a `py_func`
(what a dispatcher has), so the plain function gets both; it stays registered as jitable for any call
the pass does not reach.

The elementwise math the shared functions call goes through the shims below (`floor`, `sqrt`, `exp`, `log1p`,
`cbrt`, `copysign`, `absolute`): the NumPy ufunc itself in Python (the NumPy backend's arrays) and the same
ufunc in Numba's CPU kernels, a call LLVM inlines, so the CPU kernel gets the code it got with the ufunc written
in place (Numba's own inlining, `inline="always"`, would triple its compile time). numba-cuda has no CUDA
lowering of these ufuncs, so `kernels/cuda_target.py` gives each a libdevice one (`CUDA_SHIMS`).

`select(condition, a, b)` chooses on a path's values where a product with a mask cannot (an operand that
may be infinite or NaN, an integer result): NumPy's `where` on arrays, a plain conditional on a Numba
kernel's scalars (where `np.where` would make a 0-d array).

Without Numba installed the decorators change nothing, so the NumPy backend needs no compiler.
"""

import numpy as np


def _shim(ufunc):
    """The shim of a NumPy ufunc of one or two arguments (a plain function calling it)."""
    if ufunc.nin == 1:
        def shim(x):
            return ufunc(x)
    else:
        def shim(x, y):
            return ufunc(x, y)
    shim.__name__ = shim.__qualname__ = ufunc.__name__
    shim.__doc__ = f"np.{ufunc.__name__} here and in Numba's CPU kernels; libdevice's on CUDA (`cuda_target`)."
    shim.ufunc = ufunc
    return shim


SHIMS = floor, sqrt, exp, log1p, cbrt, copysign, absolute = tuple(
    _shim(ufunc) for ufunc in (np.floor, np.sqrt, np.exp, np.log1p, np.cbrt, np.copysign, np.absolute))


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

    def _cpu_shim(shim):
        """The CPU target's code for `shim`: its ufunc, on scalars or arrays."""
        ufunc = shim.ufunc
        if ufunc.nin == 1:
            overload(shim, target="cpu")(lambda x: lambda x: ufunc(x))
        else:
            overload(shim, target="cpu")(lambda x, y: lambda x, y: ufunc(x, y))

    for _each in SHIMS:
        _cpu_shim(_each)

    def shared_inline(function):
        shared(function)
        function.targetoptions = {"inline": "always"}
        function.py_func = function
        return function
