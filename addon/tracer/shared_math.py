"""Marks functions as shared math: plain NumPy-compatible code that the NumPy backend calls on arrays
and that Numba kernels compile in place (`numba.extending.register_jitable`).

`shared` compiles a function of its own, which LLVM inlines into its caller or calls. `shared_inline` has
Numba inline the function's code into each caller before typing on the CPU: for the trilinear look-up of the
innermost loop, the lights, the DDA and the path kernel's stages, which LLVM would call. Numba's
InlineInlinables pass inlines any global with `targetoptions` {"inline": ...} and a `py_func` (what a
dispatcher has), so the plain function gets both; it stays registered as jitable for any call the pass does not
reach. On CUDA a `shared_inline` function is not inlined before typing (its cost model says no while numba-cuda
compiles): it is a device function, typed once per signature and called, which NVVM inlines anyway. Typing the
path kernel with every stage inlined took 294 s here, with device functions 24 s, for the same registers, stack
and spills (bench/cuda_path_kernel.py). `shared_inline_always` inlines on every target: for the path state's
constructors, whose CUDA local arrays must live in the kernel's frame.

The elementwise math the shared functions call goes through the shims below (`floor`, `sqrt`, `exp`, `log1p`,
`cbrt`, `copysign`, `absolute`): the NumPy ufunc itself in Python (the NumPy backend's arrays) and the same
ufunc in Numba's CPU kernels, a call LLVM inlines, so the CPU kernel gets the code it got with the ufunc written
in place (Numba's own inlining, `inline="always"`, would triple its compile time). numba-cuda has no CUDA
lowering of these ufuncs, so `kernels/cuda_target.py` gives each a libdevice one (`CUDA_SHIMS`).

`select(condition, a, b)` chooses on a path's values where a product with a mask cannot (an operand that
may be infinite or NaN, an integer result): NumPy's `where` on arrays, a plain conditional on a Numba
kernel's scalars (where `np.where` would make a 0-d array).

A path's state and its sums go through three more shims, each plain NumPy here and in the CPU kernel:
`local_empty` and `local_zeros` (a path's buffers: the thread's local arrays on CUDA, of literal shapes) and
`accumulate` (`array[index] += value`: an atomic add on CUDA, where the threads of a pixel's samples add to
the same sums).

Without Numba installed the decorators change nothing, so the NumPy backend needs no compiler.
"""

import threading

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


def local_empty(shape, dtype):
    """`np.empty(shape, dtype)`: a path's buffer (a local array of the thread on CUDA, `cuda_target`)."""
    return np.empty(shape, dtype)


def local_zeros(shape, dtype):
    """`np.zeros(shape, dtype)`: a path's buffer (a local array of the thread on CUDA, zeroed, `cuda_target`)."""
    return np.zeros(shape, dtype)


_ADDING = threading.Lock()


def accumulate(array, index, value):
    """`array[index] += value`: a plain add in the CPU kernel, an atomic one on CUDA (`cuda_target`). In Python
    (numba-cuda's simulator, whose GPU threads are Python's) under a lock."""
    with _ADDING:
        array[index] += value


def select(condition, if_true, if_false):
    """`if_true` where `condition` holds, else `if_false` (both are evaluated)."""
    return np.where(condition, if_true, if_false)


try:
    from numba import types
    from numba.extending import overload, register_jitable as shared
except ImportError:  # the NumPy backend works without Numba

    def shared(function):
        return function

    shared_inline = shared_inline_always = shared
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

    # Compiled as small functions of their own, which LLVM inlines: never `inline="always"` on the CPU. Numba's
    # typed inlining of an overload into the path kernel corrupted the kernel (zero radiance, then a crash or an
    # endless loop on more pixels), even where the inlined call never ran; the same calls compiled as functions
    # give the kernel's sums bit for bit (docs/architecture.md, "GPU backend").
    overload(local_empty, target="cpu")(lambda shape, dtype: lambda shape, dtype: np.empty(shape, dtype))
    overload(local_zeros, target="cpu")(lambda shape, dtype: lambda shape, dtype: np.zeros(shape, dtype))

    @overload(accumulate, target="cpu")
    def _accumulate_on_cpu(array, index, value):
        def add(array, index, value):
            array[index] += value
        return add

    from numba.core.target_extension import current_target

    def _on_the_cpu(call, caller_ir, callee_ir):
        """`shared_inline`'s cost model: inline on the CPU, not while numba-cuda compiles (its target is "cuda")."""
        return current_target() != "cuda"

    def _marked(function, inline):
        shared(function)
        function.targetoptions = {"inline": inline}
        function.py_func = function
        return function

    def shared_inline(function):
        return _marked(function, _on_the_cpu)

    def shared_inline_always(function):
        return _marked(function, "always")
