"""Marks functions as shared math: plain NumPy-compatible code that the NumPy backend calls on arrays
and that Numba kernels compile in place (`numba.extending.register_jitable`).

`shared` compiles a function of its own, which LLVM inlines into its caller or calls. `shared_inline` has
Numba inline the function's code into each caller before typing, as the kernel's `jit(inline="always")`
helpers are: for the trilinear look-up of the innermost loop and the lights, which LLVM would call.
Numba's InlineInlinables pass inlines any global with `targetoptions` {"inline": "always"} and a `py_func`
(what a dispatcher has), so the plain function gets both; it stays registered as jitable for any call
the pass does not reach.

Without Numba installed the decorators change nothing, so the NumPy backend needs no compiler.
"""

try:
    from numba.extending import register_jitable as shared
except ImportError:  # the NumPy backend works without Numba

    def shared(function):
        return function

    shared_inline = shared
else:

    def shared_inline(function):
        shared(function)
        function.targetoptions = {"inline": "always"}
        function.py_func = function
        return function
