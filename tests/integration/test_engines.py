"""The C engine beside numba: the same trajectories, the engine chosen and refused clearly.

Issue 43: ``pa.simulate(..., engine="c" | "numba" | "auto")`` and ``PNEUMACT_ENGINE``; the C
engine's library is the C back end's translation of the same kernel functions, so the two
engines must agree to rounding (here: bit for bit, or 1e-12 relative where noted).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from fmu_support import needs_compiler
from pneumact.control import PID, ClosedLoop
from pneumact.core.assembly import assemble
from pneumact.core.c_engine import CKernel, engine_kernel
from pneumact.errors import ArgumentError, EngineWarning
from pneumact.experiments import SetpointStep

pytestmark = pytest.mark.integration


def _models() -> dict[str, tuple[object, pa.Experiment]]:
    vgt = load_quietly("vgt-paper")
    rig = pa.FrictionRig(load_quietly("canudas1995"), pa.LuGre(), drive="force")
    short = {"period": 4.0, "n_points": 801}
    return {
        "source": (pa.Actuator(vgt, valve=pa.PressureSource()), pa.PressureCycle(**short)),
        "command": (pa.Actuator(vgt, valve=pa.CommandValve()), pa.CommandCycle(**short)),
        "regulator": (pa.Actuator(vgt, valve=pa.PressureRegulator()),
                      pa.PressureCycle(**short)),
        "gms": (pa.Actuator(load_quietly("vgt-paper-gms4"), friction=pa.GMS(4)),
                pa.PressureCycle(**short)),
        "loop": (ClosedLoop(rig, PID(kp=3.0, ki=4.0, kd=6.0, derivative="velocity")),
                 SetpointStep(0.0, 5.0, 0.0, 10.0, 1001)),
    }


@needs_compiler
@pytest.mark.parametrize("name", ["source", "command", "regulator", "gms", "loop"])
def test_the_c_engine_follows_numba(name):
    """Every signal of the C engine's run equals numba's to 1e-12 of its range."""
    model, experiment = _models()[name]
    c = pa.simulate(model, experiment, engine="c")
    numba = pa.simulate(model, experiment, engine="numba")
    assert isinstance(assemble(model).kernel_on("c"), CKernel)
    assert (c.meta["engine"], numba.meta["engine"]) == ("c", "numba")
    assert c.meta["steps"] == numba.meta["steps"]
    a, b = c.to_pandas(), numba.to_pandas()
    assert list(a.columns) == list(b.columns)
    span = np.maximum(np.ptp(b.to_numpy(), axis=0), np.finfo(float).tiny)
    worst = np.max(np.abs(a.to_numpy() - b.to_numpy()) / span)
    assert worst <= ref.ENGINE_AGREEMENT, (name, worst)


def test_an_unknown_engine_is_refused_naming_the_choices(monkeypatch):
    model, experiment = _models()["source"]
    with pytest.raises(ArgumentError, match=r"engine = 'fast'.*auto, c, numba"):
        pa.simulate(model, experiment, engine="fast")
    monkeypatch.setenv("PNEUMACT_ENGINE", "gpu")
    with pytest.raises(ArgumentError, match=r"PNEUMACT_ENGINE = 'gpu'.*auto, c, numba"):
        pa.simulate(model, experiment)


def test_without_a_compiler_auto_runs_numba_and_says_why(monkeypatch):
    """No compiler on the machine: 'auto' warns once, naming what to install, and runs
    numba; 'c' refuses."""
    monkeypatch.setenv("CC", "no-such-compiler-here")
    model, _ = _models()["source"]
    spec = assemble(model).kernel_spec()
    with pytest.warns(EngineWarning, match="no-such-compiler-here.*numba engine runs it"):
        kernel = engine_kernel(spec, "auto")
    assert not isinstance(kernel, CKernel)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        engine_kernel(spec, "auto")  # said once per kernel and process
    with pytest.raises(pa.PneumactError, match="no-such-compiler-here"):
        engine_kernel(spec, "c")
