"""Every friction law of the registry, through everything a law must support.

The law alone (its small kernel, the law's slice at an offset in both vectors): the
partial derivatives in v, in each of its states and in each parameter of its block against
central differences; its steady states are rest points of its rates; its presliding
stiffness is what its partials say at rest. On the friction rig, every law: the
steady-state test against the law's steady force, and the presliding stiffness. In an
actuator (behind a pressure source), one law of each kernel template (a law of one state,
of none, the Maxwell-slip blocks): a run, a batch equal to single runs, forward
sensitivities of every law parameter against central differences, the linearised plant's
low-frequency gain. The template is what wires a law's functions into a model; the law's
own functions are what the law-alone tests check at an offset, so a law of a template
already run here adds nothing an actuator run would catch but ~20 s of compilation. A law
added to ``models/friction/`` is taken through all of it without touching this file;
nothing here knows how many states a law has.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
from pneumact.analysis.friction_tests import run_friction_test, solver_for
from pneumact.control import linearise
from pneumact.errors import ParameterError
from pneumact.experiments.friction import BreakAway, SteadyState
from pneumact.models import FrictionRig, LuGre, friction_models
from pneumact.simulation import assemble, simulate_sensitivities
from pneumact.simulation.batch import simulate_batch
from reference import (
    FD_REL_STEP,
    FD_SAMPLES,
    FD_SPEED_RANGE,
    FRICTION_RTOL,
    JAC_RTOL,
    LINEAR_DC_RTOL,
    PARAM_JAC_RTOL,
    SENS_FD_REL_STEP,
    SENS_NOISE_FLOOR,
    SENS_REFERENCE_RTOL,
    SENS_RMS_FRACTION,
    SENS_RTOL,
    STEADY_STATE_RTOL,
    STEADY_ZDOT_RTOL,
    STIFFNESS_RTOL,
)

#: over a minute and a half with an empty kernel cache (three kernels per law): started
#: first in a parallel run, beside the identification family, so no process waits on it
pytestmark = pytest.mark.long

LAWS = [cls() for cls in friction_models().values()]
VARIANTS = [*LAWS, LuGre(decaying_damping=True)]
#: the first law of each kernel template (registry order: LuGre, then the modules')
PER_TEMPLATE = [law for i, law in enumerate(LAWS)
                if law.template not in {earlier.template for earlier in LAWS[:i]}]
CYCLE = pa.PressureCycle(high=90e3, low=30e3, period=2.0, n_points=401)
#: a state's sample: a fraction of its steady value away from the kinks at 0 and 1
#: (Dahl and Bouc-Wen have |s| kinks there)
FRACTION_GAP = 0.05


def _with_every_law(params):
    """The set with each law's own parameters where it lacks them (GMS's blocks)."""
    for law in LAWS:
        params = params.replace(law.matched_values(params))
    return params


@pytest.fixture(scope="module")
def params(vgt):
    # central differences need both neighbours valid: Bouc-Wen's default sits on |γ| = β
    return _with_every_law(vgt.replace(bw_beta=0.6))


@pytest.fixture(scope="module")
def rig_params(canudas):
    return _with_every_law(canudas)


def _samples(law, params):
    """Velocities both ways over FD_SPEED_RANGE and states at random fractions of their
    steady values (in [−1.5, 1.5], away from 0 and 1)."""
    rng = np.random.default_rng(7)
    lo, hi = FD_SPEED_RANGE
    v = rng.choice([-1.0, 1.0], FD_SAMPLES) * np.exp(rng.uniform(np.log(lo), np.log(hi),
                                                                 FD_SAMPLES))
    steady = law.steady_states(v, params)
    fraction = rng.uniform(-1.5, 1.5, steady.shape)
    keep = np.all((np.abs(fraction) > FRACTION_GAP) & (np.abs(fraction - 1.0) > FRACTION_GAP),
                  axis=1)
    return v[keep], (fraction * steady)[keep]


def _outputs(values):
    """Rates (n, N) and force as columns (n, N + 1)."""
    return np.column_stack([values["rates"], values["force"]])


def _relative_error(analytic, numeric, here, scale):
    size = np.maximum(np.abs(numeric * scale), np.abs(here)) + 1e-300
    return np.max(np.abs(analytic - numeric) * scale / size)


@pytest.mark.parametrize("law", VARIANTS, ids=repr)
def test_law_partials_match_central_differences(law, params):
    v, y = _samples(law, params)
    here = law.evaluate(v, y, params)
    base = _outputs(here)
    analytic_v = np.column_stack([here["drates_dv"], here["dforce_dv"]])
    hv = FD_REL_STEP * np.abs(v)
    numeric_v = (_outputs(law.evaluate(v + hv, y, params))
                 - _outputs(law.evaluate(v - hv, y, params))) / (2.0 * hv[:, None])
    error = _relative_error(analytic_v, numeric_v, base, np.abs(v)[:, None])
    assert error <= JAC_RTOL, f"{law!r}: ∂/∂v off by {error:.2e}"
    scale = law.presliding_range(params)
    for j, name in enumerate(law.state_names):
        h = np.zeros_like(y)
        h[:, j] = FD_REL_STEP * scale
        numeric = (_outputs(law.evaluate(v, y + h, params))
                   - _outputs(law.evaluate(v, y - h, params))) / (2.0 * h[:, [j]])
        analytic = np.column_stack([here["drates_dy"][:, :, j], here["dforce_dy"][:, j]])
        error = _relative_error(analytic, numeric, base, scale)
        assert error <= JAC_RTOL, f"{law!r}: ∂/∂{name} off by {error:.2e}"
    partials = law.parameter_derivatives(v, y, params)
    assert set(partials) == set(law.block.names)
    for name, analytic in partials.items():
        theta = params[name]
        if theta == 0.0:
            continue
        h = FD_REL_STEP * abs(theta)
        numeric = (_outputs(law.evaluate(v, y, params.replace({name: theta + h})))
                   - _outputs(law.evaluate(v, y, params.replace({name: theta - h})))) / (2 * h)
        error = _relative_error(analytic, numeric, base, abs(theta))
        assert error <= PARAM_JAC_RTOL, f"{law!r}: ∂/∂{name} off by {error:.2e}"


@pytest.mark.parametrize("law", VARIANTS, ids=repr)
def test_steady_states_are_rest_points_and_presliding_stiffness_is_the_partials(law, params):
    lo, hi = FD_SPEED_RANGE
    speeds = np.geomspace(lo, hi, 9)
    v = np.concatenate([-speeds[::-1], speeds])
    steady = law.steady_states(v, params)
    assert steady.shape == (v.size, len(law.states))
    values = law.evaluate(v, steady, params)
    assert np.all(np.abs(values["rates"]) <= STEADY_ZDOT_RTOL * np.abs(v)[:, None])
    np.testing.assert_allclose(law.steady_force(v, params), values["force"], rtol=FRICTION_RTOL)
    # at rest each state follows the position as ∂ż_j/∂v, and carries ∂F/∂z_j of force
    rest = law.evaluate(0.0, np.zeros((1, len(law.states))), params)
    stiffness = float(np.sum(rest["dforce_dy"] * rest["drates_dv"]))
    assert stiffness == pytest.approx(law.presliding_stiffness(params), rel=FRICTION_RTOL)
    assert (law.presliding_range(params) > 0) == bool(law.states)


@pytest.fixture(scope="module", params=PER_TEMPLATE, ids=repr)
def actuator(request, params):
    law = request.param
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pa.PassivityWarning)
        model = pa.Actuator(params, friction=law, valve=pa.PressureSource())
    return law, model


def test_a_run_carries_the_law_states_and_a_batch_equals_single_runs(actuator, params):
    law, model = actuator
    names = assemble(model).state_names
    friction = [names[i] for i in assemble(model).role_states("friction")]
    assert friction == list(law.state_names)
    run = pa.simulate(model, CYCLE)
    assert np.ptp(run["position"]) > 0.0
    fc = params["Fc"]
    table = pd.DataFrame({"Fc": [0.8 * fc, fc, 1.2 * fc]})
    batch = simulate_batch(model, CYCLE, table, signals=["position"], executor=1)
    assert (batch.table["status"] == "ok").all(), batch.failed
    for row, value in enumerate(table["Fc"]):
        single = pa.simulate(model, CYCLE, values={"Fc": value})
        np.testing.assert_array_equal(batch.signals["position"][row], single["position"])


def test_sensitivities_of_every_law_parameter_match_central_differences(actuator, params):
    law, model = actuator
    names = [n for n in law.block.parameters if params[n] != 0.0]
    if law.sensitivity_refusal is not None:  # refused, with the law's reason
        with pytest.raises(ParameterError, match=re.escape(law.sensitivity_refusal)):
            simulate_sensitivities(model, CYCLE, names)
        return
    sens = simulate_sensitivities(model, CYCLE, names, pa.Rodas4(rtol=SENS_RTOL))
    tight = pa.Rodas4(rtol=SENS_REFERENCE_RTOL)
    for k, name in enumerate(names):
        step = SENS_FD_REL_STEP * abs(params[name])
        up = pa.simulate(model, CYCLE, tight, values={name: params[name] + step})
        down = pa.simulate(model, CYCLE, tight, values={name: params[name] - step})
        fd = (up["position"] - down["position"]) / (2 * step)
        rms = np.sqrt(np.mean((sens["position"][:, k] - fd) ** 2))
        allowed = max(SENS_RMS_FRACTION * np.max(np.abs(fd)),
                      SENS_NOISE_FLOOR["position"] / abs(params[name]))
        assert rms <= allowed, f"{law!r}: ∂position/∂{name} RMS error {rms:.2e} > {allowed:.2e}"


def test_linearised_gain_at_rest_is_the_spring_beside_the_presliding_stiffness(actuator,
                                                                                params):
    """Δx/Δp → A_d/(k + presliding stiffness) as ω → 0: friction at rest is a spring in
    parallel with the actuator's (none for a static map)."""
    law, model = actuator
    plant = linearise(model, 60e3)
    stiffness = params["k"] + law.presliding_stiffness(params)
    omega = 1e-6 * np.sqrt(stiffness / params["m"])
    resolvent = np.linalg.solve(1j * omega * np.eye(plant.A.shape[0]) - plant.A, plant.B)
    gain = abs((plant.C @ resolvent).item())
    assert gain == pytest.approx(params["A_d"] / stiffness, rel=LINEAR_DC_RTOL)


@pytest.mark.parametrize("law", LAWS, ids=repr)
def test_rig_steady_state_test_gives_the_law_steady_force(law, rig_params):
    test = SteadyState(speeds=(1e-4, 1e-3, 1e-2))
    table = run_friction_test(test, rig_params, law).table
    np.testing.assert_allclose(table["friction [N]"], table["steady-state friction [N]"],
                               rtol=STEADY_STATE_RTOL)


@pytest.mark.parametrize("law", [law for law in LAWS if law.states], ids=repr)
def test_rig_presliding_stiffness_is_the_law_presliding_stiffness(law, rig_params):
    test = BreakAway(rates=(0.03,), final_force=0.01 * rig_params["Fs"], n_points=2001)
    (setup,) = test.setups(rig_params, law)
    run = pa.simulate(FrictionRig(rig_params, law, "force"), setup.experiment,
                      solver_for(test, rig_params, law))
    late = run.time >= 0.05
    slope = np.polyfit(run["drive_force"][late], run["position"][late], 1)[0]
    assert 1.0 / slope == pytest.approx(law.presliding_stiffness(rig_params),
                                        rel=STIFFNESS_RTOL)
