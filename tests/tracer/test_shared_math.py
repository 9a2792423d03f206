"""`shared_math`: a `shared_inline` function is inlined into its Numba callers (Numba's untyped
InlineInlinables pass takes it for a dispatcher), while a `shared` one is compiled on its own and called;
NumPy callers get the plain functions."""

import numpy as np
import pytest

from addon.tracer.shared_math import shared, shared_inline

numba = pytest.importorskip("numba")


@shared_inline
def _clamp(x):
    return np.minimum(np.maximum(x, 0.0), 1.0)


@shared
def _clamp_called(x):
    return np.minimum(np.maximum(x, 0.0), 1.0)


def _typed_calls(dispatcher):
    """What the dispatcher's compiled code calls, as Numba typed it: inlined functions are not among them
    (their bodies' calls are)."""
    annotation = dispatcher.overloads[dispatcher.signatures[0]].type_annotation
    return [str(annotation.typemap[call.func.name]) for call in annotation.calltypes
            if getattr(call, "op", "") == "call"]


def test_shared_inline_is_inlined_and_shared_is_called():
    @numba.njit
    def caller(x):
        return _clamp(x) + 2.0 * _clamp_called(x)

    assert caller(0.25) == 0.75
    calls = _typed_calls(caller)
    assert not any("_clamp " in call for call in calls)
    assert any("_clamp_called " in call for call in calls)
    assert any("minimum" in call for call in calls)  # _clamp's own call, inlined


def test_numpy_callers_get_the_plain_functions():
    values = np.array([-1.0, 0.5, 2.0])
    np.testing.assert_array_equal(_clamp(values), [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(_clamp_called(values), [0.0, 0.5, 1.0])
