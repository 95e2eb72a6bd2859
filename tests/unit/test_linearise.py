"""``control.linear.linearise``: A and B against central differences of the kernel's ``rhs``
(not its analytic ``jac``), the presliding and sliding points, closed-form gains, errors,
and the python-control round trip."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

import pneumact as pa
from pneumact.control.linear import LinearPlant, linearise, plot_bode
from pneumact.core.assembly import assemble
from pneumact.core.signals import Constant, pack_channels
from pneumact.errors import ExperimentError, ParameterError
from reference import (
    LIN_B_FD_REL_STEP,
    LIN_DC_GAIN_RTOL,
    LIN_FD_REL_STEP,
    LIN_FD_RTOL,
    LIN_POLE_RTOL,
    LIN_RESPONSE_RTOL,
    LIN_SLIDING_VELOCITY,
)

COMMAND = 0.6  # mid-stroke rest of vgt-paper behind the command valve (x ≈ 5.5 mm)


@pytest.fixture(scope="module")
def actuator(vgt):
    return pa.Actuator(vgt, pa.LuGre(), valve=pa.CommandValve())


@pytest.fixture(scope="module")
def rig(canudas):
    return pa.FrictionRig(canudas, pa.LuGre(), drive="force")


def _point(lin: LinearPlant) -> np.ndarray:
    return np.array([lin.operating_point[n] for n in lin.state_names])


def _rhs(plant, y, u):
    assembly = assemble(plant)
    sig, ptr = pack_channels(plant.channels(Constant(u)))
    f = np.empty_like(y)
    assembly.kernel.rhs(0.0, 0.0, y, assembly.pack(), sig, ptr, f)
    return f


def _check_against_differences(plant, lin: LinearPlant, u: float, input_scale: float):
    """A column by column and B by central differences of rhs, each compared, scaled by
    the state scales, with the largest entry of its row."""
    y0 = _point(lin)
    scales = lin.state_scales
    n = y0.size
    numeric = np.zeros((n, n))
    for j in range(n):
        h = LIN_FD_REL_STEP * max(abs(y0[j]), scales[j])
        up, down = y0.copy(), y0.copy()
        up[j] += h
        down[j] -= h
        numeric[:, j] = (_rhs(plant, up, u) - _rhs(plant, down, u)) / (2.0 * h)
    du = LIN_B_FD_REL_STEP * max(abs(u), input_scale)
    b = (_rhs(plant, y0, u + du) - _rhs(plant, y0, u - du)) / (2.0 * du)
    full_num = np.column_stack([numeric * scales, b])
    full_lin = np.column_stack([lin.A * scales, lin.B[:, 0]])
    size = np.max(np.abs(full_num), axis=1, keepdims=True) + 1e-300
    error = np.abs(full_lin - full_num) / size
    worst = np.unravel_index(np.argmax(error), error.shape)
    assert error.max() <= LIN_FD_RTOL, (
        f"{lin.regime}: entry {worst} linearised {full_lin[worst]:.9g}, differences "
        f"{full_num[worst]:.9g}")
    return error.max()


@pytest.mark.parametrize("regime", ["presliding", "sliding"])
def test_actuator_matrices_match_differences(actuator, regime):
    velocity = LIN_SLIDING_VELOCITY if regime == "sliding" else None
    lin = linearise(actuator, COMMAND, regime=regime, velocity=velocity)
    assert lin.state_names == ("position", "velocity", "bristle", "pressure")
    assert lin.input_name == "command" and lin.input_unit == "1"
    _check_against_differences(actuator, lin, COMMAND, 1.0)
    assert np.array_equal(lin.C, [[1.0, 0.0, 0.0, 0.0]]) and np.array_equal(lin.D, [[0.0]])


@pytest.mark.parametrize(("force", "regime"), [(0.0, "presliding"), (0.5, "presliding"),
                                               (0.5, "sliding")])
def test_rig_matrices_match_differences(rig, canudas, force, regime):
    velocity = -LIN_SLIDING_VELOCITY if regime == "sliding" else None
    lin = linearise(rig, force, regime=regime, velocity=velocity,
                    outputs=("position", "velocity"))
    _check_against_differences(rig, lin, force, 1.0)
    if regime == "presliding":  # the bristle carries the force: σ0·z = F, at rest
        assert lin.operating_point["bristle"] == pytest.approx(force / canudas["sigma0"])
        assert np.max(np.abs(lin.rates)) <= 1e-12


def test_sliding_changes_the_friction_rows(actuator, vgt):
    pre = linearise(actuator, COMMAND)
    v = LIN_SLIDING_VELOCITY
    slide = linearise(actuator, COMMAND, regime="sliding", velocity=v)
    iv, iz = pre.state_names.index("velocity"), pre.state_names.index("bristle")
    # presliding: the bristle is an integrator of v (∂ż/∂z = 0) under spring σ0, damping σ1+σ2
    assert pre.A[iz, iz] == 0.0 and pre.A[iz, iv] == 1.0
    assert pre.A[iv, iz] == pytest.approx(-vgt["sigma0"] / vgt["m"], rel=1e-12)
    # sliding: ∂ż/∂z = −σ0·|v|/g(v), the bristle relaxes; the point moves at v
    g = vgt["Fc"] + (vgt["Fs"] - vgt["Fc"]) * math.exp(-((v / vgt["vs"]) ** vgt["delta"]))
    assert slide.A[iz, iz] == pytest.approx(-vgt["sigma0"] * v / g, rel=1e-12)
    assert slide.operating_point["bristle"] == pytest.approx(g / vgt["sigma0"], rel=1e-12)
    for row in (iv, iz):
        assert not np.allclose(pre.A[row], slide.A[row], rtol=1e-3, atol=0.0)
    assert pre.equilibrium and not slide.equilibrium
    assert slide.rates[pre.state_names.index("position")] == v
    assert "sliding" in slide.statement and "not an equilibrium" in slide.statement
    assert "presliding" in pre.statement and "equilibrium" in pre.statement


def test_rig_presliding_closed_form(rig, canudas):
    """Presliding rig: m·ẍ = F − σ0·x − (σ1 + σ2)·ẋ, so x/F = 1/(m s² + (σ1+σ2) s + σ0)."""
    lin = linearise(rig, 0.0)
    m, s0, damping = canudas["m"], canudas["sigma0"], canudas["sigma1"] + canudas["sigma2"]
    assert lin.dc_gain() == pytest.approx(1.0 / s0, rel=LIN_DC_GAIN_RTOL)
    f = np.array([1.0, 30.0, 50.0, 300.0])
    s = 2j * np.pi * f
    expected = 1.0 / (m * s**2 + damping * s + s0)
    assert np.allclose(lin.frequency_response(f), expected, rtol=LIN_RESPONSE_RTOL, atol=0.0)
    poles = np.sort_complex(lin.poles())
    roots = np.sort_complex(np.append(np.roots([m, damping, s0]), 0.0))
    assert np.allclose(poles, roots, rtol=LIN_POLE_RTOL, atol=LIN_POLE_RTOL * abs(roots[0]))


def test_actuator_dc_gain_adds_the_bristle_stiffness(actuator, vgt):
    """Presliding, the bristle stiffens the spring: x/u = k/(k + σ0) × d(rest position)/du
    (the rest position moves with friction unloaded, against k alone)."""
    assembly = assemble(actuator)
    kernel, vec = assembly.kernel, assembly.pack()

    def rest(u):
        y = np.empty(len(assembly.states))
        kernel.initial_state(0.0, 0.0, vec, *pack_channels(actuator.channels(Constant(u))), y)
        return y[0]

    du = 1e-6
    slope = (rest(COMMAND + du) - rest(COMMAND - du)) / (2 * du)
    k, s0 = vgt["k"], vgt["sigma0"]
    lin = linearise(actuator, COMMAND)
    assert lin.dc_gain() == pytest.approx(slope * k / (k + s0), rel=LIN_DC_GAIN_RTOL)
    # the x − z pole at the origin cancels: finite gain, equal to the response at low f
    assert abs(lin.frequency_response(1e-6)) == pytest.approx(lin.dc_gain(), rel=1e-6)


def test_free_mass_has_infinite_dc_gain():
    """x/F = 1/(m s² + c s): the position integrates (inf), the velocity settles at 1/c;
    with c = 0 (a defective pole at the origin) both diverge."""
    for c, velocity_gain in ((3.0, 1.0 / 3.0), (0.0, math.inf)):
        params = pa.ParameterSet.from_dict({"m": 2.0, "Fc": 0.0, "sigma2": c})
        rig = pa.FrictionRig(params, pa.CoulombViscous(), drive="force")
        gains = linearise(rig, 0.0, outputs=("position", "velocity")).dc_gain()
        assert gains[0] == math.inf
        assert gains[1] == pytest.approx(velocity_gain, rel=LIN_DC_GAIN_RTOL)


def test_to_control_round_trip(actuator):
    control = pytest.importorskip("control")
    lin = linearise(actuator, COMMAND)
    sys_ = lin.to_control()
    assert isinstance(sys_, control.StateSpace)
    assert list(sys_.input_labels) == ["command"]
    assert list(sys_.output_labels) == ["position"]
    assert list(sys_.state_labels) == list(lin.state_names)
    poles = np.sort_complex(lin.poles())
    assert np.allclose(np.sort_complex(sys_.poles()), poles, rtol=LIN_POLE_RTOL,
                       atol=LIN_POLE_RTOL * np.max(np.abs(poles)))
    f = np.array([0.3, 3.0, 30.0])
    mine = lin.frequency_response(f)
    theirs = np.array([sys_(2j * np.pi * fk) for fk in f]).ravel()
    assert np.allclose(mine, theirs, rtol=LIN_RESPONSE_RTOL, atol=0.0)


def test_to_pandas_is_the_system_matrix(actuator):
    lin = linearise(actuator, COMMAND)
    frame = lin.to_pandas()
    assert frame.shape == (5, 5)
    assert frame.loc[("d/dt", "pressure"), ("input", "command")] == lin.B[3, 0]
    assert frame.loc[("output", "position"), ("state", "position")] == 1.0
    assert frame.attrs["regime"] == "presliding"


def test_missing_python_control_says_how_to_install(actuator, monkeypatch):
    monkeypatch.setitem(sys.modules, "control", None)
    with pytest.raises(ImportError, match=r"pip install 'pneumact\[control\]'"):
        linearise(actuator, COMMAND).to_control()


@pytest.mark.parametrize(("kwargs", "error", "words"), [
    ({"outputs": ("stroke",)}, ParameterError, "outputs.*stroke.*allowed.*position"),
    ({"regime": "stiction"}, ParameterError, "regime.*stiction.*allowed.*presliding"),
    ({"regime": "sliding"}, ParameterError, "velocity = None.*sliding"),
    ({"regime": "sliding", "velocity": 0.0}, ParameterError, "velocity = 0.0"),
    ({"velocity": 1e-3}, ParameterError, "velocity.*only with regime='sliding'"),
    ({"input_value": 1.2}, ExperimentError, r"input_value = 1.2.*allowed.*\[0, 1\]"),
    ({"input_value": -0.1}, ExperimentError, r"input_value = -0.1.*allowed.*\[0, 1\]"),
    ({"input_value": float("nan")}, ExperimentError, "input_value = nan"),
])
def test_bad_input_is_named(actuator, kwargs, error, words):
    kwargs = {"input_value": COMMAND, **kwargs}
    u = kwargs.pop("input_value")
    with pytest.raises(error, match=words):
        linearise(actuator, u, **kwargs)


def test_plants_without_a_rest_or_an_input(rig, canudas):
    with pytest.raises(ExperimentError, match=r"holds no presliding rest.*sliding"):
        linearise(rig, 2.0 * canudas["Fs"])
    with pytest.raises(ParameterError, match="drive='force'"):
        linearise(pa.FrictionRig(canudas, pa.LuGre(), drive="velocity"), 0.0)


def test_input_range_ends_use_one_sided_differences(actuator):
    """At u = 0 and u = 1 the valve's area maps are flat outside [0, 1]: B comes from the
    inside (a central difference would halve it)."""
    for u in (0.0, 1.0):
        lin = linearise(actuator, u)
        y0 = _point(lin)
        du = 1e-4 * (1.0 if u == 0.0 else -1.0)
        inside = (_rhs(actuator, y0, u + du) - _rhs(actuator, y0, u)) / du
        assert lin.B[3, 0] == pytest.approx(inside[3], rel=1e-6)


def test_plot_bode_states_the_regime(actuator):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd

    lin = linearise(actuator, COMMAND)
    g = lin.frequency_response([1.0, 5.0])
    measured = pd.DataFrame({"frequency_hz": [1.0, 5.0], "amplitude": [1e-4, 1e-4],
                             "gain": np.abs(g), "phase_deg": np.degrees(np.angle(g)) + 360})
    fig = plot_bode(lin, measured)
    try:
        assert len(fig.axes) == 2
        assert "Presliding" in fig.axes[0].get_title()
        phase_points = fig.axes[1].lines[1].get_ydata()
        assert np.allclose(phase_points, np.degrees(np.angle(g)))  # moved by whole turns
    finally:
        plt.close(fig)
