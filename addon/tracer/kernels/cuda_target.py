"""The CUDA target, every CUDA specific in one place: the compiler (numba-cuda), compiling a function to PTX
for a compute capability without a GPU, assembling that PTX to see the resources a kernel takes, and whether a
usable device and driver exist.

Nothing here is imported with the tracer: numba-cuda is imported on the first call of `compiler()`, so the
tracer and the extension (whose zip does not bundle numba-cuda) work where it is absent. The compiler is
numba-cuda, not numba-cuda-mlir (docs/architecture.md, "GPU backend", says why): a switch
changes `_import_compiler` and the module names of the two patches below.

Two patches make numba-cuda 0.30 compile on a machine without a GPU and with NumPy 2.5, each applied only
where it is needed:
- NumPy 2.5 removed `np.row_stack`, which numba-cuda's array module overloads when its typing context is
  first built: the alias (`np.vstack`) exists while that module is imported, then is removed again.
- Compiling a device function that calls another asks the current device for its compute capability; without
  a driver there is none, so where no device is usable the dispatcher and the compiler are told of a device
  of `COMPUTE_CAPABILITY`. The PTX itself is generated for the capability `compile_ptx` is given.
"""

import functools
import importlib
import re
import types
import warnings

import numpy as np

from .. import shared_math
from ..errors import SpectralError

COMPUTE_CAPABILITY = (9, 0)  # what the PTX is checked for without a GPU: an H100/H200 (sm_90)
PACKAGES = "numba-cuda, cuda-bindings, cuda-core, cuda-pathfinder, nvidia-nvvm, nvidia-cuda-nvrtc and nvidia-nvjitlink"
MISSING = f"The CUDA backend needs numba-cuda: install {PACKAGES} (pinned in requirements.lock)."
# The libdevice function of each `shared_math` shim on one path's float64 scalars (numba-cuda lowers none of
# these NumPy ufuncs).
CUDA_SHIMS = {shared_math.floor: "floor", shared_math.sqrt: "sqrt", shared_math.exp: "exp",
              shared_math.log1p: "log1p", shared_math.cbrt: "cbrt", shared_math.copysign: "copysign",
              shared_math.absolute: "fabs"}


def _import_compiler():
    """numba-cuda's `numba.cuda` module, with its array module imported (see the module docstring)."""
    with warnings.catch_warnings():  # numba-cuda 0.30's NumPy datetime helpers use a deprecated unit
        warnings.filterwarnings("ignore", "The 'generic' unit for NumPy timedelta", DeprecationWarning)
        cuda = importlib.import_module("numba.cuda")
        if getattr(cuda, "implementation", None) != "NVIDIA":  # Numba's own, deprecated CUDA target
            raise ImportError("numba.cuda is Numba's built-in target, not numba-cuda")
        if not hasattr(np, "row_stack"):
            np.row_stack = np.vstack
            try:
                importlib.import_module("numba.cuda.np.arrayobj")
            finally:
                del np.row_stack
    return cuda


def _local_array(cuda, zeroed):
    """The CUDA code of `shared_math.local_empty` (`zeroed` False) or `local_zeros`: a local array of the thread,
    of the literal shape given, inlined into its caller (its storage is the kernel's frame). It is zeroed by
    loops over its axes: a reshape calls Numba's runtime, which PTX lacks."""
    from numba.core import types
    from numba.core.errors import TypingError

    def typer(shape, dtype):
        kinds = shape.types if isinstance(shape, types.BaseTuple) else (shape,)
        if not all(isinstance(kind, types.IntegerLiteral) for kind in kinds):
            raise TypingError(f"a CUDA local array needs a literal shape, not {shape}")
        dims = tuple(kind.literal_value for kind in kinds)
        element = dtype.dtype
        if len(dims) == 1:
            def impl(shape, dtype):
                array = cuda.local.array(dims, element)
                if zeroed:
                    for a in range(dims[0]):
                        array[a] = 0
                return array
        elif len(dims) == 2:
            def impl(shape, dtype):
                array = cuda.local.array(dims, element)
                if zeroed:
                    for a in range(dims[0]):
                        for b in range(dims[1]):
                            array[a, b] = 0
                return array
        else:
            def impl(shape, dtype):
                array = cuda.local.array(dims, element)
                if zeroed:
                    for a in range(dims[0]):
                        for b in range(dims[1]):
                            for c in range(dims[2]):
                                array[a, b, c] = 0
                return array
        return impl

    return typer


def _register_shims(cuda):
    """The CUDA target's code for every `shared_math` shim: libdevice's function for the elementwise math (on
    scalars), local arrays for a path's buffers, atomic adds for its sums."""
    from numba.core.types import Number
    from numba.cuda import libdevice
    from numba.cuda.extending import overload

    overload(shared_math.local_empty, target="cuda", inline="always", prefer_literal=True)(_local_array(cuda, False))
    overload(shared_math.local_zeros, target="cuda", inline="always", prefer_literal=True)(_local_array(cuda, True))
    overload(shared_math.accumulate, target="cuda")(
        lambda array, index, value: lambda array, index, value: cuda.atomic.add(array, index, value))

    def register(shim, device_function):
        if shim.ufunc.nin == 1:
            overload(shim, target="cuda")(
                lambda x: (lambda x: device_function(x)) if isinstance(x, Number) else None)
        else:
            overload(shim, target="cuda")(
                lambda x, y: (lambda x, y: device_function(x, y))
                if isinstance(x, Number) and isinstance(y, Number) else None)

    for shim, name in CUDA_SHIMS.items():
        register(shim, getattr(libdevice, name))


@functools.cache
def compiler():
    """numba-cuda's `numba.cuda`, ready to compile here (a `SpectralError` naming what to install when absent).
    Under `NUMBA_ENABLE_CUDASIM=1`, set before the first import, it is numba-cuda's simulator."""
    try:
        cuda = _import_compiler()
    except ImportError as error:
        raise SpectralError(f"{MISSING} ({error})") from error
    if not simulating():  # the simulator runs the shims' Python
        _register_shims(cuda)
    if not cuda.is_available():  # no driver or no device (the simulator is always available)
        device = types.SimpleNamespace(compute_capability=COMPUTE_CAPABILITY)
        for name in ("numba.cuda.dispatcher", "numba.cuda.compiler"):
            importlib.import_module(name).get_current_device = lambda: device
    return cuda


def simulating() -> bool:
    """Whether numba-cuda is its simulator (NUMBA_ENABLE_CUDASIM=1 when it was first imported): kernels run as
    Python, on NumPy's arrays."""
    return bool(importlib.import_module("numba.cuda.core.config").ENABLE_CUDASIM)


def compile_ptx(function, argument_types, cc=COMPUTE_CAPABILITY, device=False, opt=True):
    """PTX of `function` (plain Python, or a `shared_math.shared` function) for the Numba types
    `argument_types`, compiled for compute capability `cc` without a GPU: a device function when `device`, else
    a kernel; NVVM optimises it unless `opt` is False. Returns (PTX text, return type)."""
    return compiler().compile_ptx(function, tuple(argument_types), device=device, cc=cc, opt=opt)


def assemble(ptx, cc=COMPUTE_CAPABILITY):
    """Assemble PTX for compute capability `cc` as the driver would (ptxas, through nvJitLink: no GPU needed) and
    return what its kernel takes per thread: {"registers", "stack" (bytes), "spills" (bytes stored), "constant"
    (bytes of constant bank 3, where global arrays go)}. Raises `RuntimeError` with ptxas's log if it fails."""
    from cuda.bindings import nvjitlink

    handle = nvjitlink.create(2, [f"-arch=sm_{cc[0]}{cc[1]}", "-verbose"])
    try:
        try:
            nvjitlink.add_data(handle, nvjitlink.InputType.PTX, ptx.encode(), len(ptx), "kernel.ptx")
            nvjitlink.complete(handle)
        except nvjitlink.nvJitLinkError as error:
            log = bytearray(nvjitlink.get_error_log_size(handle))
            nvjitlink.get_error_log(handle, log)
            raise RuntimeError(f"ptxas failed: {log.decode(errors='replace')}") from error
        log = bytearray(nvjitlink.get_info_log_size(handle))
        nvjitlink.get_info_log(handle, log)
    finally:
        nvjitlink.destroy(handle)
    text = log.decode(errors="replace")

    def figure(pattern):
        found = re.findall(pattern, text)
        return max(map(int, found)) if found else 0

    # The linked kernel's line ("info : used 46 registers, used 5 barriers, 40 stack, ..."), not ptxas's per
    # function ones; spills are ptxas's (the most any function stores).
    return {"registers": figure(r"info\s*: used (\d+) registers"), "stack": figure(r"info\s*: used .*?(\d+) stack"),
            "spills": figure(r"(\d+) bytes spill stores"), "constant": figure(r"(\d+) bytes cmem\[3\]")}


def device_problem():
    """None where a CUDA device and driver are usable; else why not, in a sentence a user can act on."""
    try:
        cuda = compiler()
    except SpectralError as error:
        return str(error)
    if not cuda.is_available():
        return ("No usable CUDA device: the NVIDIA driver or a GPU is missing (numba-cuda found no CUDA driver "
                "library or no device). Render with the CPU backend instead.")
    return None


def require_device():
    """numba-cuda's `numba.cuda` where a device is usable; else a `SpectralError` saying why not."""
    problem = device_problem()
    if problem:
        raise SpectralError(problem)
    return compiler()
