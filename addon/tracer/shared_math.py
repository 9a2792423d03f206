"""Marks functions as shared math: plain NumPy-compatible code that the NumPy backend calls on arrays
and that Numba kernels compile in place (`numba.extending.register_jitable`).

`shared` compiles a function of its own, which LLVM inlines into its caller or calls; `shared_inline`
has Numba inline it into each caller, for the trilinear look-up of the innermost loop, which LLVM would
call. (Numba inlines such functions after typing, at a cost in compile time at every call site: the
exception, not the rule.)

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
        return shared(inline="always")(function)  # a fresh decorator each time: register_jitable's keeps state
