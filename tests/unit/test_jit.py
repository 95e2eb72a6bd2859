"""``core.jit.njit``: numba functions declared without importing numba (issue 43's warm
command), made on first use, and called from compiled code as numba's own."""

from __future__ import annotations

import pickle
import subprocess
import sys

import pytest

from pneumact.core import features
from pneumact.core.jit import LazyDispatcher, dispatcher_of, is_compiled_function, njit

pytestmark = pytest.mark.unit


@njit(inline="always")
def _halve(x):
    return 0.5 * x


@njit
def _plus_one(x):
    return x + 1.0


@njit(cache=False)
def _calls_both(x):
    return _halve(x) + _plus_one(x)


def test_a_function_is_made_on_first_use_only():
    @njit
    def square(x):
        return x * x

    assert isinstance(square, LazyDispatcher) and not square.made
    assert square.__name__ == "square" and square.py_func(3.0) == 9.0  # no numba needed
    assert getattr(square, "__kernel_options__", None) is None  # probing makes nothing
    assert not square.made
    assert square(3.0) == 9.0 and square.made
    assert len(square.signatures) == 1  # numba's dispatcher, reached through the stand-in


def test_compiled_code_calls_stand_ins_as_numba_functions():
    """numba types a global stand-in as the dispatcher it makes (inlined or called)."""
    assert _calls_both(4.0) == pytest.approx(2.0 + 5.0)
    assert _halve.made and _plus_one.made
    assert _halve.dispatcher().targetoptions["inline"] == "always"
    assert dispatcher_of(_plus_one) is _plus_one.dispatcher()
    assert is_compiled_function(_plus_one) and is_compiled_function(_plus_one.dispatcher())
    assert not is_compiled_function(_plus_one.py_func)


def test_a_stand_in_pickles_as_its_module_s_function():
    assert pickle.loads(pickle.dumps(features.all_features)) is features.all_features


def test_bad_arguments_are_refused():
    with pytest.raises(TypeError, match="keyword options only"):
        njit("float64(float64)")


def test_importing_pneumact_and_building_a_model_does_not_import_numba():
    script = ("import sys, pneumact as pa; "
              "pa.Actuator(pa.load_params('vgt-paper'), valve=pa.CommandValve()); "
              "print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-W", "ignore", "-c", script], check=True,
                         capture_output=True, text=True, timeout=120).stdout
    assert out.strip() == "False"
