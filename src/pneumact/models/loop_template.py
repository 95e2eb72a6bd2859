"""Model template: a closed loop, a plant (actuator, cylinder or friction rig) under a
controller.

The plant's own template is bound under the prefix ``plant_`` (``codegen.Child``): its
states come first in the loop's state vector and its functions read them where they
always do. The controller (``pneumact.models.controllers``; states after the plant's,
settings in the ``controller`` block) computes the plant's input from the position
set-point (channel CH_SETPOINT: after the plant's channels, so where the plant declares
channels of its own, ``core.channels``, the generator sets CH_SETPOINT, CH_FEEDFORWARD
and CH_DISTURBANCE in the kernel), the measured position and velocity, a cylinder's
pressure difference (``plant_pressure_feedback``, under PRESSURE_FEEDBACK) and its own
states.
Before every call of a plant function the loop writes that input into the plant's
drive channel, a one-point channel of this run's own input buffer: the plant's code
reads its input exactly as in an open-loop run.

A continuous controller integrates with the plant. A sampled one (``SAMPLED``) is
updated by ``jump`` at every sample time t = k·T_s (the integrators stop there) and
holds its output in between (zero-order hold); its states then have zero rates.
"""

import math
from collections import namedtuple

import numpy as np

from pneumact.core import kernel
from pneumact.core.channels import (
    CH_DISTURBANCE,
    CH_DRIVE,
    CH_FEEDFORWARD,
    CH_SETPOINT,
    INPUT_OFFSET,
)
from pneumact.core.signals import channel_eval
from pneumact.models.controllers import (
    CT_ACTION,
    CT_ANTI_WINDUP,
    CT_BIAS,
    CT_CASCADE,
    CT_COMP,
    CT_DERIVATIVE,
    CT_DITHER_A,
    CT_DITHER_F,
    CT_FF_DELTA,
    CT_FF_FC,
    CT_FF_FS,
    CT_FF_VS,
    CT_FF_VSMOOTH,
    CT_GAIN,
    CT_KD,
    CT_KDP,
    CT_KI,
    CT_KP,
    CT_KX,
    CT_OBS_FC,
    CT_OBS_FS,
    CT_OBS_K,
    CT_OBS_S0,
    CT_OBS_S1,
    CT_OBS_S2,
    CT_OBS_VS,
    CT_TF,
    CT_TS,
    CT_TT,
    CT_UMAX,
    CT_UMIN,
    CT_VFF,
)

# --- bound by the generator --------------------------------------------------------------
plant_rhs = plant_jac = plant_param_jac = plant_outputs = plant_initial_state = None
plant_project = plant_state_scales = plant_derive = None
#: a plant with two chambers defines it (a cylinder): the pressure difference its piston
#: feels, read under PRESSURE_FEEDBACK only
plant_pressure_feedback = None
OPTIONAL_FUNCTIONS = ("plant_pressure_feedback",)
PRESSURE_FEEDBACK = False
NSTATE = 4
NPARAM = 0
NOUT = None  # generated: the plant's outputs and the loop's
PLANT_NSTATE = 3
PLANT_NOUT = 0
CONTROLLER_LO = 0
CONTROLLER_HI = 0
S_POSITION = 0
S_VELOCITY = 1
S_CONTROL_INTEGRAL = 3
S_DERIVATIVE_FILTER = -1
S_FRICTION_ESTIMATE_BRISTLE = -1
S_HELD_COMMAND = -1
S_LAST_POSITION = -1
SAMPLED = False
FILTERED_DERIVATIVE = False
DIFFERENCE_VELOCITY = False
OBSERVER = False
#: the feed-forward and disturbance channels are read only when given: their code in
#: the hot path costs a quarter of a closed-loop run even when it does not execute
HAS_LOOP_INPUTS = False
# ------------------------------------------------------------------------------------------

#: the loop's own outputs, after the plant's
LOOP_OUTPUTS = ("position_setpoint", "error", "command", "plant_input", "friction_compensation")
#: generated from the loop's output names (after the plant's): OUT_<NAME>
OUT_POSITION_SETPOINT = OUT_ERROR = OUT_COMMAND = OUT_PLANT_INPUT = OUT_FRICTION_COMPENSATION = None
#: relative step of the finite differences of the Jacobian's coupling terms
COUPLING_FD = 1e-7
#: clamping anti-windup: width of the output layer over which the integrator stops,
#: relative to the limit (an error of at most this much in the output)
CLAMP_LAYER = 1e-4
#: |t − k·T_s| below which a breakpoint is the sample k
SAMPLE_MATCH = 1e-6


#: The control law at one instant: the limited and unlimited output, the integrator's
#: rate, the derivative filter's input, the observer's dẑ/dt = a − b·ẑ, the friction
#: compensation F̂, the set-point and the error.
LawValue = namedtuple("LawValue", ["output", "unlimited", "integrator_rate", "filter_input",
                                   "observer_a", "observer_b", "friction_estimate",
                                   "setpoint", "error"])


@kernel()
def _observer(v, zhat, e, prm):
    """(a, b, F̂): dẑ/dt = a − b·ẑ of the LuGre observer and its force estimate."""
    c = CONTROLLER_LO
    s0 = prm[c + CT_OBS_S0]
    fc = prm[c + CT_OBS_FC]
    g = fc + (prm[c + CT_OBS_FS] - fc) * math.exp(-((v / prm[c + CT_OBS_VS]) ** 2))
    a = v + prm[c + CT_OBS_K] * e
    b = s0 * abs(v) / g
    zrate = a - b * zhat
    return a, b, s0 * zhat + prm[c + CT_OBS_S1] * zrate + prm[c + CT_OBS_S2] * v


@kernel()
def _static_ff(rdot, prm):
    """Steady friction at the reference velocity, sign rounded over v_smooth."""
    c = CONTROLLER_LO
    fc = prm[c + CT_FF_FC]
    speed = abs(rdot) / prm[c + CT_FF_VS]
    level = fc + (prm[c + CT_FF_FS] - fc) * math.exp(-(speed ** prm[c + CT_FF_DELTA]))
    return math.tanh(rdot / prm[c + CT_FF_VSMOOTH]) * level


@kernel()
def _law(t, ts, x, v, dp, integral, filt, zhat, prm, sig, ptr):
    """The control law at one instant (a ``LawValue``), from the measured x, v, the
    plant's pressure difference dp (zero without one) and the controller's states."""
    c = CONTROLLER_LO
    r, rdot = channel_eval(sig, ptr, CH_SETPOINT, t, ts)
    e = r - x
    ki = prm[c + CT_KI]
    q = 0.0
    derivative = prm[c + CT_DERIVATIVE]
    if prm[c + CT_CASCADE] > 0.5:
        ev = prm[c + CT_KX] * e + prm[c + CT_VFF] * rdot - v
        terms = prm[c + CT_KP] * ev + ki * integral
        integrand = ev
    else:
        terms = prm[c + CT_KP] * e + ki * integral + prm[c + CT_VFF] * rdot
        integrand = e
        if FILTERED_DERIVATIVE:
            q = e if derivative == 1.0 else -x
            terms += prm[c + CT_KD] * (q - filt) / prm[c + CT_TF]
        elif derivative == 3.0:
            terms -= prm[c + CT_KD] * v
    terms -= prm[c + CT_KDP] * dp
    act = prm[c + CT_ACTION]
    u = prm[c + CT_BIAS] + act * terms
    if HAS_LOOP_INPUTS:
        u += channel_eval(sig, ptr, CH_FEEDFORWARD, t, ts)[0]
    f_hat = 0.0
    if prm[c + CT_FF_FC] != 0.0 or prm[c + CT_FF_FS] != 0.0:  # static compensation
        f_hat = _static_ff(rdot, prm)
    obs_a = 0.0
    obs_b = 0.0
    if OBSERVER:
        obs_a, obs_b, f_obs = _observer(v, zhat, e, prm)
        f_hat += f_obs
    u += prm[c + CT_COMP] * f_hat
    if prm[c + CT_DITHER_A] != 0.0:
        u += prm[c + CT_DITHER_A] * math.sin(2.0 * math.pi * prm[c + CT_DITHER_F] * t)
    u_sat = min(max(u, prm[c + CT_UMIN]), prm[c + CT_UMAX])
    rate = integrand
    anti_windup = prm[c + CT_ANTI_WINDUP]
    if anti_windup == 1.0 and ki != 0.0:
        rate += act * (u_sat - u) / (ki * prm[c + CT_TT])
    elif anti_windup == 2.0 and u_sat != u and (u - u_sat) * act * ki * integrand > 0.0:
        # stop integrating while pushing into the limit; faded out over a thin layer of
        # the output, since a switched rate would chatter on the limit (Filippov sliding)
        layer = CLAMP_LAYER * max(abs(u_sat), 1.0)
        rate = integrand * max(1.0 - abs(u - u_sat) / layer, 0.0)
    return LawValue(u_sat, u, rate, q, obs_a, obs_b, f_hat, r, e)


@kernel()
def _pressure_difference(y, prm):
    """The plant's pressure difference for the state feedback (zero without two
    chambers)."""
    if PRESSURE_FEEDBACK:
        return plant_pressure_feedback(y, prm)
    return 0.0


@kernel()
def _states_law(t, ts, y, prm, sig, ptr):
    """The continuous law read from the state vector."""
    filt = y[S_DERIVATIVE_FILTER] if FILTERED_DERIVATIVE else 0.0
    zhat = y[S_FRICTION_ESTIMATE_BRISTLE] if OBSERVER else 0.0
    return _law(t, ts, y[S_POSITION], y[S_VELOCITY], _pressure_difference(y, prm),
                y[S_CONTROL_INTEGRAL], filt, zhat, prm, sig, ptr)


@kernel()
def _command(t, ts, y, prm, sig, ptr):
    """The controller output acting now: held (sampled) or the continuous law's."""
    if SAMPLED:
        return y[S_HELD_COMMAND]
    return _states_law(t, ts, y, prm, sig, ptr).output


@kernel()
def _plant_input(t, ts, command, prm, sig, ptr):
    value = prm[CONTROLLER_LO + CT_GAIN] * command
    if HAS_LOOP_INPUTS:
        value += channel_eval(sig, ptr, CH_DISTURBANCE, t, ts)[0]
    return value


@kernel()
def _write_input(t, ts, command, prm, sig, ptr):
    """Write the plant's input for ``command`` into its drive channel; return it."""
    value = _plant_input(t, ts, command, prm, sig, ptr)
    sig[ptr[CH_DRIVE] + INPUT_OFFSET] = value
    return value


@kernel()
def _apply(t, ts, y, prm, sig, ptr):
    """Write the plant's input for (t, y) into its drive channel; return it."""
    return _write_input(t, ts, _command(t, ts, y, prm, sig, ptr), prm, sig, ptr)


@kernel()
def derive(prm):
    plant_derive(prm)


@kernel()
def _rates_of(law, y, prm, dydt):
    """The continuous controller's state rates from one evaluation of the law."""
    dydt[S_CONTROL_INTEGRAL] = law.integrator_rate
    if FILTERED_DERIVATIVE:
        dydt[S_DERIVATIVE_FILTER] = ((law.filter_input - y[S_DERIVATIVE_FILTER])
                                     / prm[CONTROLLER_LO + CT_TF])
    if OBSERVER:
        dydt[S_FRICTION_ESTIMATE_BRISTLE] = (law.observer_a - law.observer_b
                                             * y[S_FRICTION_ESTIMATE_BRISTLE])


@kernel()
def rhs(t, ts, y, prm, sig, ptr, dydt):
    """The plant under the controller's input, then the controller's rates; the law is
    evaluated once."""
    if SAMPLED:
        _write_input(t, ts, y[S_HELD_COMMAND], prm, sig, ptr)
        plant_rhs(t, ts, y, prm, sig, ptr, dydt)
        for i in range(PLANT_NSTATE, NSTATE):
            dydt[i] = 0.0
        return
    law = _states_law(t, ts, y, prm, sig, ptr)
    _write_input(t, ts, law.output, prm, sig, ptr)
    plant_rhs(t, ts, y, prm, sig, ptr, dydt)
    for i in range(PLANT_NSTATE, NSTATE):
        dydt[i] = 0.0
    _rates_of(law, y, prm, dydt)


@kernel()
def _input_gain(t, ts, y, value, prm, sig, ptr, b):
    """b = ∂f_plant/∂input at the plant input ``value`` (written in its channel), by a
    forward difference of the plant's right-hand side."""
    f0 = np.empty(NSTATE)
    f1 = np.empty(NSTATE)
    plant_rhs(t, ts, y, prm, sig, ptr, f0)
    dv = COUPLING_FD * max(abs(value), 1.0)
    sig[ptr[CH_DRIVE] + INPUT_OFFSET] = value + dv
    plant_rhs(t, ts, y, prm, sig, ptr, f1)
    sig[ptr[CH_DRIVE] + INPUT_OFFSET] = value
    for a in range(PLANT_NSTATE):
        b[a] = (f1[a] - f0[a]) / dv


@kernel()
def _input_and_rates(t, ts, y, prm, sig, ptr, rates):
    """The plant input and the controller's rates at (y, prm): one side of a difference.
    The continuous law is evaluated once for both (the Jacobian calls this twice per
    state: evaluating it apart for the rates and the command was a tenth of a loop's
    run)."""
    for i in range(PLANT_NSTATE, NSTATE):
        rates[i] = 0.0
    if SAMPLED:
        return _plant_input(t, ts, y[S_HELD_COMMAND], prm, sig, ptr)
    law = _states_law(t, ts, y, prm, sig, ptr)
    _rates_of(law, y, prm, rates)
    return _plant_input(t, ts, law.output, prm, sig, ptr)


@kernel()
def jac(t, ts, y, prm, sig, ptr, out):
    """∂f/∂y: the plant's analytic Jacobian at its present input, plus the coupling
    through the controller, (∂f_plant/∂input)·(∂input/∂y), and the controller's rows,
    both by finite differences of the (cheap) law."""
    value = _apply(t, ts, y, prm, sig, ptr)
    plant_jac(t, ts, y, prm, sig, ptr, out)
    b = np.empty(PLANT_NSTATE)
    _input_gain(t, ts, y, value, prm, sig, ptr, b)
    scales = np.empty(NSTATE)
    state_scales(prm, scales)
    yp = y.copy()
    r0 = np.empty(NSTATE)
    r1 = np.empty(NSTATE)
    for j in range(NSTATE):
        h = COUPLING_FD * max(abs(y[j]), scales[j])
        yp[j] = y[j] + h
        up = _input_and_rates(t, ts, yp, prm, sig, ptr, r1)
        yp[j] = y[j] - h
        down = _input_and_rates(t, ts, yp, prm, sig, ptr, r0)
        yp[j] = y[j]
        slope = (up - down) / (2.0 * h)
        if slope != 0.0:
            for a in range(PLANT_NSTATE):
                out[a, j] += b[a] * slope
        for a in range(PLANT_NSTATE, NSTATE):
            out[a, j] = (r1[a] - r0[a]) / (2.0 * h)


@kernel()
def param_jac(t, ts, y, prm, sig, ptr, g, needed):
    """∂f/∂prm: the plant's at its present input; for the controller's parameters (a
    continuous controller's: a sampled one acts through its jumps), the coupling
    (∂f_plant/∂input)·(∂input/∂prm) and the controller's rows, by central differences
    of the law."""
    value = _apply(t, ts, y, prm, sig, ptr)
    plant_param_jac(t, ts, y, prm, sig, ptr, g, needed)
    for a in range(PLANT_NSTATE, NSTATE):
        for k in range(g.shape[1]):
            g[a, k] = 0.0
    if SAMPLED:
        return
    wanted = False
    for k in range(CONTROLLER_LO, CONTROLLER_HI):
        wanted = wanted or needed[k]
    if not wanted:
        return
    b = np.empty(PLANT_NSTATE)
    _input_gain(t, ts, y, value, prm, sig, ptr, b)
    moved = prm.copy()
    r0 = np.empty(NSTATE)
    r1 = np.empty(NSTATE)
    for k in range(CONTROLLER_LO, CONTROLLER_HI):
        if not needed[k]:
            continue
        h = COUPLING_FD * (abs(prm[k]) if prm[k] != 0.0 else 1.0)
        moved[k] = prm[k] + h
        up = _input_and_rates(t, ts, y, moved, sig, ptr, r1)
        moved[k] = prm[k] - h
        down = _input_and_rates(t, ts, y, moved, sig, ptr, r0)
        moved[k] = prm[k]
        slope = (up - down) / (2.0 * h)
        for a in range(PLANT_NSTATE):
            g[a, k] = b[a] * slope
        for a in range(PLANT_NSTATE, NSTATE):
            g[a, k] = (r1[a] - r0[a]) / (2.0 * h)


@kernel()
def outputs(t, ts, y, prm, sig, ptr, out):
    """The plant's outputs, then set-point, error, command, plant input and the
    friction compensation F̂ the law holds at this instant."""
    law = _states_law(t, ts, y, prm, sig, ptr)
    command = y[S_HELD_COMMAND] if SAMPLED else law.output
    value = _write_input(t, ts, command, prm, sig, ptr)
    plant_outputs(t, ts, y, prm, sig, ptr, out)
    out[OUT_POSITION_SETPOINT] = law.setpoint
    out[OUT_ERROR] = law.error
    out[OUT_COMMAND] = command
    out[OUT_PLANT_INPUT] = value
    out[OUT_FRICTION_COMPENSATION] = law.friction_estimate


@kernel()
def initial_state(t, ts, prm, sig, ptr, y0):
    """The plant at rest under the bias input, the controller's states at zero (its held
    output at the bias)."""
    bias = prm[CONTROLLER_LO + CT_BIAS]
    _write_input(t, ts, bias, prm, sig, ptr)
    plant_initial_state(t, ts, prm, sig, ptr, y0)
    for i in range(PLANT_NSTATE, NSTATE):
        y0[i] = 0.0
    if SAMPLED:
        y0[S_HELD_COMMAND] = bias
        if DIFFERENCE_VELOCITY:
            y0[S_LAST_POSITION] = y0[S_POSITION]


@kernel()
def jump(t, ts, y, prm, sig, ptr):
    """At a sample time: sample x (and v, or its difference estimate), compute and hold
    the output, then advance the controller's states over one period (forward Euler
    for the integrator, the exact filter and observer updates for a constant input)."""
    c = CONTROLLER_LO
    period = prm[c + CT_TS]
    k = round(t / period)
    if abs(t - k * period) > SAMPLE_MATCH * period:
        return
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    if DIFFERENCE_VELOCITY:
        v = (x - y[S_LAST_POSITION]) / period
        y[S_LAST_POSITION] = x
    filt = y[S_DERIVATIVE_FILTER] if FILTERED_DERIVATIVE else 0.0
    zhat = y[S_FRICTION_ESTIMATE_BRISTLE] if OBSERVER else 0.0
    law = _law(t, ts, x, v, _pressure_difference(y, prm), y[S_CONTROL_INTEGRAL], filt, zhat,
               prm, sig, ptr)
    y[S_HELD_COMMAND] = law.output
    y[S_CONTROL_INTEGRAL] += period * law.integrator_rate
    if FILTERED_DERIVATIVE:
        y[S_DERIVATIVE_FILTER] = filt + period / (prm[c + CT_TF] + period) * (law.filter_input
                                                                               - filt)
    if OBSERVER:
        obs_a = law.observer_a
        obs_b = law.observer_b
        if obs_b * period > 1e-12:
            steady = obs_a / obs_b
            y[S_FRICTION_ESTIMATE_BRISTLE] = steady + (zhat - steady) * math.exp(-obs_b * period)
        else:
            y[S_FRICTION_ESTIMATE_BRISTLE] = zhat + obs_a * period


@kernel()
def project(prm, y):
    plant_project(prm, y)


@kernel()
def state_scales(prm, out):
    """The plant's scales; the controller's from the position scale (its integrator:
    that scale over one second) and the observer's presliding range."""
    plant_state_scales(prm, out)
    position = out[S_POSITION]
    for i in range(PLANT_NSTATE, NSTATE):
        out[i] = position
    if OBSERVER:
        out[S_FRICTION_ESTIMATE_BRISTLE] = (prm[CONTROLLER_LO + CT_OBS_FS]
                                            / prm[CONTROLLER_LO + CT_OBS_S0])
    if SAMPLED:
        scale = max(abs(prm[CONTROLLER_LO + CT_BIAS]), 1.0)
        out[S_HELD_COMMAND] = scale
