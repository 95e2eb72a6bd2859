"""Template: the compiled integrators, bound to one model by the generator.

``integrate_rodas4``: Hairer & Wanner's RODAS (order 4, embedded 3), a 6-stage,
L-stable, stiffly accurate Rosenbrock method with the model's analytic Jacobian; the
default. ``integrate_rodas4_sens`` is the same loop carrying forward sensitivities
ds/dt = J·s + ∂f/∂θ (compiled only when first used: the plain run passes ``None`` and
numba prunes the sensitivity code from it). ``integrate_dopri5``: Dormand-Prince 5(4),
explicit, for non-stiff variants. One driver (``_integrate``) runs them all: the breakpoint
intervals, jumps, step control, dense output and sensitivities are written once, and
only a step attempt is the method's own.

All integrate interval by interval between breakpoints (corners and jumps of the
inputs, the samples of a digital controller) and control the step on a per-state
rtol/atol. A model with sampled parts (``HAS_JUMPS``) updates them by its ``jump`` at
the start of every interval: the held states jump there and stay constant inside. At
the requested output times they write

- the states, by cubic Hermite interpolation of each step (shape-preserving for the
  states a component declares bounded, such as the bristle deflection);
- the model's derived outputs, by shape-preserving cubic interpolation between their
  exact values at the ends of the step, so an output never leaves the range the model
  gives it at the solver's steps (friction force, flows), whatever the tolerance.

They never raise: ``info`` reports the status, where and how the run failed.

``integrate_rodas4_states`` and ``integrate_dopri5_states`` are the same runs without the
derived outputs (``out`` is ``None``, and numba prunes every branch that computes them):
the batch engine calls them where what it keeps is states only (the features read
position, velocity and pressure, states of an actuator), saving three ``outputs`` calls
per step that writes output points. The states are the same bit for bit: the outputs
never feed back into the steps.
"""

import math
from collections import namedtuple

import numpy as np

from pneumact.core import kernel
from pneumact.core.linalg import lu_det_sign, lu_factor, lu_solve

# --- bound by the generator and the model template ---------------------------------------
rhs = jac = outputs = param_jac = derive = project = jump = None
event_guards = event_switch = None
#: only a model with jumps defines ``jump`` (it is called under ``HAS_JUMPS``), only one
#: with events ``event_guards`` and ``event_switch`` (under ``HAS_EVENTS``)
OPTIONAL_FUNCTIONS = ("jump", "event_guards", "event_switch")
#: a model with a sampled part (a digital controller) updates it at breakpoints
HAS_JUMPS = False
#: a model with state events (a hybrid friction law's stick/slip switches) switches
#: where its guards cross zero, located on each step's interpolant
HAS_EVENTS = False
NSTATE = 3
NOUT = None  # generated from the model's outputs
NPARAM = 0
MONOTONE = (False, False, False)
# ------------------------------------------------------------------------------------------

STATUS_OK = 0
STATUS_STEP_UNDERFLOW = 1
STATUS_NON_FINITE = 2
STATUS_MAX_STEPS = 3
STATUS_TEXT = {
    STATUS_STEP_UNDERFLOW: "step size underflow (the solution changes faster than the "
                           "tolerances allow)",
    STATUS_NON_FINITE: "the state became non-finite (NaN or inf)",
    STATUS_MAX_STEPS: "maximum number of steps reached",
}
# info layout
INFO_STATUS = 0
INFO_T = 1
INFO_STEPS = 2
INFO_REJECTED = 3
INFO_RHS = 4
INFO_JAC = 5
INFO_H = 6
INFO_LENGTH = 8
#: |cubic term| / (|m0| + |m1| + |Δ|) up to which an interpolating cubic is trusted
CUBIC_TRUST = 0.5
#: h·J_ii allowed for a state that feeds itself (J_ii > 0): a growing mode is followed
UNSTABLE_STEP = 0.5
#: relative step of the finite differences in time (∂f/∂t) and along the trajectory
TIME_FD = 1.4901161193847656e-08
OUTPUT_FD = 1e-7
#: relative distance below a breakpoint from which an output point waits for its jump
JUMP_EDGE = 1e-12
#: relative step (of each parameter's value) of the jump's directional differences
JUMP_FD = 1e-6
#: an event located within this fraction of a step's end ends that step; an earlier one
#: cuts the step there (the step is taken again, ending at the event). A step already cut
#: at an event ends at it if it is found again within EVENT_CUT_EDGE of the end: the
#: shorter step's interpolant puts the crossing a little elsewhere, and cutting again
#: for each such shift would shorten it without end.
EVENT_EDGE = 1e-9
EVENT_CUT_EDGE = 1e-3
#: bisections of the step fraction that locate an event (2^-42 of the step)
EVENT_BISECTIONS = 42

# RODAS (Hairer & Wanner 1996, rodas.f METH=1)
GAM = 0.25
C2, C3, C4 = 0.386, 0.21, 0.63
D1, D2, D3, D4 = 0.25, -0.1043, 0.1035, -0.3620000000000023e-01
A21 = 0.1544000000000000e01
A31, A32 = 0.9466785280815826e00, 0.2557011698983284e00
A41, A42, A43 = 0.3314825187068521e01, 0.2896124015972201e01, 0.9986419139977817e00
A51, A52 = 0.1221224509226641e01, 0.6019134481288629e01
A53, A54 = 0.1253708332932087e02, -0.6878860361058950e00
G21 = -0.5668800000000000e01
G31, G32 = -0.2430093356833875e01, -0.2063599157091915e00
G41, G42, G43 = -0.1073529058151375e00, -0.9594562251023355e01, -0.2047028614809616e02
G51, G52 = 0.7496443313967647e01, -0.1024680431464352e02
G53, G54 = -0.3399990352819905e02, 0.1170890893206160e02
G61, G62, G63 = 0.8083246795921522e01, -0.7981132988064893e01, -0.3152159432874371e02
G64, G65 = 0.1631930543123136e02, -0.6058818238834054e01
#: A[i, j]: stage i reads k_j (stage 6 adds k_5 to stage 5's state: stiffly accurate).
#: Global arrays are frozen into the compiled code as constants.
STAGE_A = np.array([[0.0, 0.0, 0.0, 0.0, 0.0], [A21, 0.0, 0.0, 0.0, 0.0],
                    [A31, A32, 0.0, 0.0, 0.0], [A41, A42, A43, 0.0, 0.0],
                    [A51, A52, A53, A54, 0.0], [A51, A52, A53, A54, 1.0]])
STAGE_G = np.array([[0.0, 0.0, 0.0, 0.0, 0.0], [G21, 0.0, 0.0, 0.0, 0.0],
                    [G31, G32, 0.0, 0.0, 0.0], [G41, G42, G43, 0.0, 0.0],
                    [G51, G52, G53, G54, 0.0], [G61, G62, G63, G64, G65]])
STAGE_C = np.array([0.0, C2, C3, C4, 1.0, 1.0])
STAGE_D = np.array([D1, D2, D3, D4, 0.0, 0.0])


# --------------------------------------------------------------------------- dense output
@kernel()
def _error_norm(err, y, ynew, rtol, atol, n):
    s = 0.0
    for i in range(n):
        sc = atol[i] + rtol * max(abs(y[i]), abs(ynew[i]))
        e = err[i] / sc
        s += e * e
    return math.sqrt(s / n)


@kernel()
def _limited(y0, m0, y1, m1):
    """Slopes (× step) for a cubic Hermite that never leaves what the step's ends say.

    Where the cubic term is small against the slopes (a smooth solution, an extremum
    inside the step) the slopes are kept: full accuracy. Where it dominates (end slopes
    that do not represent the step, as when an output is read off a stiff transient at a
    loose tolerance) they are limited as Fritsch and Carlson do, so the cubic stays
    between y0 and y1.
    """
    delta = y1 - y0
    if abs(m0 + m1 - 2.0 * delta) <= CUBIC_TRUST * (abs(m0) + abs(m1) + abs(delta)):
        return m0, m1
    if delta == 0.0:
        return 0.0, 0.0
    alpha = max(m0 / delta, 0.0)
    beta = max(m1 / delta, 0.0)
    r2 = alpha * alpha + beta * beta
    if r2 > 9.0:
        tau = 3.0 / math.sqrt(r2)
        alpha *= tau
        beta *= tau
    return alpha * delta, beta * delta


@kernel()
def _hermite(th):
    """The cubic Hermite weights at th ∈ [0, 1] of y0, m0, y1, m1 (slopes × step)."""
    u = 1.0 - th
    return (1.0 + 2.0 * th) * u * u, th * u * u, th * th * (3.0 - 2.0 * th), th * th * (th - 1.0)


@kernel()
def _output_rate(t, ts, y, f, eps, prm, sig, ptr, o, do, ybuf, obuf):
    """The rate of the outputs ``o`` (at (t, y)) along the trajectory (f = dy/dt there),
    by a difference of step ``eps`` that points into the step: forward at its start,
    backward at its end, so a kink or a jump of an input at the step's edge is not seen
    from the wrong side."""
    for i in range(NSTATE):
        ybuf[i] = y[i] + eps * f[i]
    outputs(t + eps, ts, ybuf, prm, sig, ptr, obuf)
    for k in range(NOUT):
        do[k] = (obuf[k] - o[k]) / eps


@kernel()
def _dense(t0, h, y0, f0, y1, f1, o0, do0, o1, do1, t_out, j, t_stop, y_out, out, slopes,
           prm):
    """Write every requested time in (t0, t0 + h] (and ≤ t_stop); returns the next j.

    ``slopes`` (2 × (NSTATE + NOUT)) receives the step's slopes, limited where needed;
    interpolated states are projected onto the model's invariant bounds like the steps.
    ``out`` ``None``: states only (the outputs' values and rates are not read)."""
    for i in range(NSTATE):
        m0, m1 = h * f0[i], h * f1[i]
        if MONOTONE[i]:
            m0, m1 = _limited(y0[i], m0, y1[i], m1)
        slopes[0, i] = m0
        slopes[1, i] = m1
    if out is not None:
        for k in range(NOUT):
            slopes[0, NSTATE + k], slopes[1, NSTATE + k] = _limited(o0[k], h * do0[k],
                                                                    o1[k], h * do1[k])
    n_out = t_out.shape[0]
    while j < n_out and t_out[j] <= t_stop and t_out[j] <= t0 + h:
        # y0 + h01·(y1 − y0) + ...: the Hermite form with h00 = 1 − h01, exact for a
        # flat step (a held command stays exactly at its limit)
        _, h10, h01, h11 = _hermite((t_out[j] - t0) / h)
        for i in range(NSTATE):
            y_out[j, i] = (y0[i] + h01 * (y1[i] - y0[i]) + h10 * slopes[0, i]
                           + h11 * slopes[1, i])
        project(prm, y_out[j])
        if out is not None:
            for k in range(NOUT):
                out[j, k] = (o0[k] + h01 * (o1[k] - o0[k]) + h10 * slopes[0, NSTATE + k]
                             + h11 * slopes[1, NSTATE + k])
        j += 1
    return j


@kernel()
def _write_point(t, ts, y, prm, sig, ptr, y_out, out, j):
    """Output row j at a step's end: the state and (``out`` not ``None``) the outputs
    there."""
    for i in range(NSTATE):
        y_out[j, i] = y[i]
    if out is not None:
        outputs(t, ts, y, prm, sig, ptr, out[j])


@kernel()
def _write_after_jump(t, ts, y, prm, sig, ptr, t_out, j, y_out, out):
    """Output points at a breakpoint of a model with jumps take the state after the jump
    (a held value is right-continuous, as a zero-order hold's output is)."""
    n_out = t_out.shape[0]
    while j < n_out and t_out[j] <= t:
        _write_point(t, ts, y, prm, sig, ptr, y_out, out, j)
        j += 1
    return j


@kernel()
def _finish(info, status, t, steps, rejected, n_rhs, n_jac, h):
    info[INFO_STATUS] = status
    info[INFO_T] = t
    info[INFO_STEPS] = steps
    info[INFO_REJECTED] = rejected
    info[INFO_RHS] = n_rhs
    info[INFO_JAC] = n_jac
    info[INFO_H] = h


# --------------------------------------------------------------------------- RODAS4
@kernel()
def _unstable_step_limit(jm, n):
    """Longest step that follows a self-amplifying state: UNSTABLE_STEP / max(J_ii)."""
    rate = 0.0
    for a in range(n):
        rate = max(rate, jm[a, a])
    return UNSTABLE_STEP / rate if rate > 0.0 else math.inf


@kernel()
def e_of(jm, h, e, n):
    """E = I/(h·γ) − J, the matrix every RODAS stage solves with."""
    fac = 1.0 / (h * GAM)
    for a in range(n):
        for b in range(n):
            e[a, b] = -jm[a, b]
        e[a, a] += fac
    return e


@kernel()
def _rodas_stages(t, h, ts, y, f0, ft, e, piv, prm, sig, ptr, ks, yst, fst, fb):
    """The six stages of one RODAS step from (t, y); ks[i]: the stage increments,
    yst[i]/fst[i]: the stage states and their right-hand sides."""
    n = NSTATE
    inv_h = 1.0 / h
    for st in range(6):
        for a in range(n):
            acc = y[a]
            for jj in range(st):
                acc += STAGE_A[st, jj] * ks[jj, a]
            yst[st, a] = acc
        if st == 0:
            for a in range(n):
                fb[a] = f0[a]
        else:
            rhs(t + STAGE_C[st] * h, ts, yst[st], prm, sig, ptr, fb)
        for a in range(n):
            fst[st, a] = fb[a]
            acc = fb[a] + h * STAGE_D[st] * ft[a]
            for jj in range(st):
                acc += STAGE_G[st, jj] * inv_h * ks[jj, a]
            ks[st, a] = acc
        lu_solve(e, piv, ks[st], n)


@kernel(nogil=True)
def integrate_rodas4(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps,
                     y_out, out, info):
    """Integrate from tb[0] to tb[-1]; return the final state (the failing one on error)."""
    return _integrate(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps,
                  y_out, out, info, None, None)


@kernel(nogil=True)
def integrate_rodas4_states(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max,
                            max_steps, y_out, info):
    """``integrate_rodas4`` writing the states only (no derived outputs): the same states,
    bit for bit, without the outputs' cost."""
    return _integrate(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps,
                  y_out, None, info, None, None)


@kernel(nogil=True)
def integrate_rodas4_sens(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max,
                          max_steps, y_out, out, info, w_ptr, w_idx, w_val, needed, s0,
                          s_out):
    """RODAS4 with forward sensitivities s = dy/dθ for P parameters.

    ∂f/∂θ_p = Σ_k G[:, w_idx[k]]·w_val[k] over k in [w_ptr[p], w_ptr[p+1]): the model's
    ∂f/∂prm (``param_jac``) times how each parameter moves the vector, derived slots
    included. ``needed`` flags the vector slots that occur. ``s0`` (n × P): the initial
    sensitivity; ``s_out`` (n × n_out × P) receives them at ``t_out``.
    """
    return _integrate(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps,
                  y_out, out, info, SensInput(w_ptr, w_idx, w_val, needed, s0, s_out), None)


@kernel(nogil=True)
def integrate_dopri5(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps,
                     y_out, out, info):
    """Explicit adaptive Dormand-Prince 5(4); same interface as ``integrate_rodas4``."""
    n = NSTATE
    return _integrate(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps,
                  y_out, out, info, None, DopriWork(np.empty(n), np.empty(n)))


@kernel()
def _first_event(t, h, ts, y, f0, ynew, f1, prm, sig, ptr, g_start, g_end, g_mid, ybuf,
                 at):
    """The fraction of the step at which the first guard crosses zero (2.0 if none does),
    by bisection on the step's cubic Hermite interpolant; ``at[i]``: guard i's crossing
    (2.0 if it does not cross)."""
    count = event_guards(t + h, ts, ynew, prm, sig, ptr, g_end)
    first = 2.0
    for i in range(count):
        at[i] = 2.0
        if not (g_start[i] > 0.0 and g_end[i] <= 0.0):
            continue
        lo = 0.0
        hi = 1.0
        for _ in range(EVENT_BISECTIONS):
            mid = 0.5 * (lo + hi)
            h00, h10, h01, h11 = _hermite(mid)
            for a in range(NSTATE):
                ybuf[a] = h00 * y[a] + h01 * ynew[a] + h * (h10 * f0[a] + h11 * f1[a])
            event_guards(t + mid * h, ts, ybuf, prm, sig, ptr, g_mid)
            if g_mid[i] > 0.0:
                lo = mid
            else:
                hi = mid
        at[i] = hi
        first = min(first, hi)
    return first


@kernel()
def _mark_events(at, first, forced, count, cut):
    """Flag the guards that cross at ``first``: they replace the flags when the step is
    cut there, and join those of the cut step that now ends at its event."""
    for i in range(count):
        here = at[i] <= min(first + EVENT_EDGE, 1.0)
        forced[i] = here if cut else (forced[i] or here)


@kernel(nogil=True)
def integrate_dopri5_states(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max,
                            max_steps, y_out, info):
    """``integrate_dopri5`` writing the states only, as ``integrate_rodas4_states``."""
    n = NSTATE
    return _integrate(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps,
                  y_out, None, info, None, DopriWork(np.empty(n), np.empty(n)))


#: Dormand-Prince's work arrays: a stage's state (cont) and the error estimate (err).
#: ``None`` in their place selects RODAS4.
DopriWork = namedtuple("DopriWork", ["cont", "err"])


@kernel()
def _integrate(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps, y_out, out,
           info, sens, dopri):
    """The one integration loop of every method: breakpoint intervals and jumps, step
    attempts and their control, dense output, forward sensitivities. ``dopri`` holds
    Dormand-Prince 5(4)'s work arrays, ``None`` selects RODAS4; ``sens`` is ``None`` in a
    plain run. numba prunes the branches of an argument that is ``None`` (not those of
    one that is not): the default method and a plain run compile only their own code."""
    n = NSTATE
    derive(prm)
    y = y0.copy()
    ynew = np.empty(n)
    f1 = np.empty(n)
    ks = np.empty((6, n))
    # RODAS4: the Jacobian, the iteration matrix and its pivots, the stage states and
    # rates, f at t + dt and ∂f/∂t
    jm = np.zeros((n, n))
    e = np.empty((n, n))
    piv = np.zeros(n, dtype=np.int64)
    yst = np.empty((6, n))
    fst = np.empty((6, n))
    fb = np.empty(n)
    ft = np.empty(n)
    if dopri is None:
        f0 = np.empty(n)
    else:  # f(t, y) is Dormand-Prince's first stage (FSAL)
        f0 = ks[0]
    ybuf = np.empty(n)
    obuf = np.empty(NOUT)
    o0 = np.empty(NOUT)
    do0 = np.empty(NOUT)
    o1 = np.empty(NOUT)
    do1 = np.empty(NOUT)
    slopes = np.empty((2, NSTATE + NOUT))
    if sens is not None:
        work = _sens_work(sens.s0.shape[1])
        s = sens.s0.copy()
    for i in range(INFO_LENGTH):
        info[i] = 0.0
    n_out = t_out.shape[0]
    h = h_init
    steps = 0
    rejected = 0
    n_rhs = 0
    n_jac = 0
    # an int64 from the start, not the literal 0: a call that first sees j = 0 would
    # compile a second copy of the function it calls, for that constant
    j = np.int64(0)
    t = tb[0]
    while not HAS_JUMPS and j < n_out and t_out[j] <= t:
        _write_point(t, 0.5 * (tb[0] + tb[1]), y, prm, sig, ptr, y_out, out, j)
        if sens is not None:
            _sens_point(s, sens.s_out, j)
        j += 1
    status = STATUS_OK
    just_rejected = False
    h_acc = 0.0
    err_acc = 1.0
    # events: the guards at the step's start and end, a bisection's guards, the blocks
    # located at the end of a cut step (switched there whatever their guard's round-off)
    g_start = np.empty(n)
    g_end = np.empty(n)
    g_mid = np.empty(n)
    at = np.full(n, 2.0)
    forced = np.zeros(n, dtype=np.bool_)
    event_cut = False
    for seg in range(tb.shape[0] - 1):
        t = tb[seg]
        t_end = tb[seg + 1]
        if t_end <= t:
            continue
        ts = 0.5 * (t + t_end)
        t_stop = t_end
        if HAS_JUMPS:
            if sens is not None:
                _sens_jump(t, ts, y, prm, sig, ptr, sens, s)
            jump(t, ts, y, prm, sig, ptr)
            j_before = j
            j = _write_after_jump(t, ts, y, prm, sig, ptr, t_out, j, y_out, out)
            if sens is not None:
                for jj in range(j_before, j):
                    _sens_point(s, sens.s_out, jj)
            if seg < tb.shape[0] - 2:  # a point on the next breakpoint: after its jump
                t_stop = t_end - JUMP_EDGE * max(1.0, abs(t_end))
        if HAS_EVENTS:  # the interval's inputs (a reversal of a prescribed motion) decide
            event_switch(t, ts, y, prm, sig, ptr, forced)
            event_guards(t, ts, y, prm, sig, ptr, g_start)
        rhs(t, ts, y, prm, sig, ptr, f0)
        n_rhs += 1
        jm_valid = False
        ft_valid = False
        o0_valid = False
        if sens is not None:
            n_jac += _sens_segment(t, ts, y, prm, sig, ptr, sens, work, s)
        while t < t_end:
            if steps >= max_steps:
                status = STATUS_MAX_STEPS
                break
            if dopri is None:
                # Jacobian and time derivative (forward difference inside the segment);
                # both are kept after a rejected step (same t, y)
                if not jm_valid:
                    for a in range(n):
                        for b in range(n):
                            jm[a, b] = 0.0
                    jac(t, ts, y, prm, sig, ptr, jm)
                    n_jac += 1
                    jm_valid = True
                if not ft_valid:
                    dt = TIME_FD * max(abs(t), 1e-3)
                    rhs(t + dt, ts, y, prm, sig, ptr, fb)
                    n_rhs += 1
                    for a in range(n):
                        ft[a] = (fb[a] - f0[a]) / dt
                    ft_valid = True
                # an unstable mode (negative damping as a slip starts) must be followed,
                # not damped away by a long L-stable step: a state that feeds itself
                # (J_ii > 0) limits h·J_ii, and det(E) < 0 (a real eigenvalue above
                # 1/(h·γ)) rejects
                h = min(h, h_max, _unstable_step_limit(jm, n))
            else:
                h = min(h, h_max)
            last = False
            if t + h >= t_end - 1e-3 * h and not (HAS_EVENTS and event_cut):
                h = t_end - t
                last = True
            t_new = t_end if last else t + h
            if dopri is None:
                if (not lu_factor(e_of(jm, h, e, n), piv, n)
                        or lu_det_sign(e, piv, n) < 0.0):
                    h *= 0.5
                    rejected += 1
                    if h < 1e-14 * max(1.0, abs(t)):
                        status = STATUS_STEP_UNDERFLOW
                        break
                    continue
                _rodas_stages(t, h, ts, y, f0, ft, e, piv, prm, sig, ptr, ks, yst, fst, fb)
                err, finite = _rodas_solution(y, ks, yst, ynew, rtol, atol)
                n_rhs += 5
                if err <= 1.0:
                    project(prm, ynew)
                    rhs(t_new, ts, ynew, prm, sig, ptr, f1)
                    n_rhs += 1
            else:
                _dopri_stages(t, h, ts, y, prm, sig, ptr, ks, dopri.cont)
                finite = True
                for a in range(n):
                    acc = 0.0
                    for st in range(6):
                        acc += DP_W[st] * ks[st, a]
                    ynew[a] = y[a] + h * acc
                    if not math.isfinite(ynew[a]):
                        finite = False
                err = math.inf
                if finite:
                    project(prm, ynew)
                    rhs(t_new, ts, ynew, prm, sig, ptr, f1)
                    for a in range(n):
                        acc = E7 * f1[a]
                        for st in range(6):
                            acc += DP_E[st] * ks[st, a]
                        dopri.err[a] = h * acc
                    err = _error_norm(dopri.err, y, ynew, rtol, atol, n)
                n_rhs += 6
            if HAS_EVENTS and err <= 1.0:
                theta = _first_event(t, h, ts, y, f0, ynew, f1, prm, sig, ptr, g_start, g_end,
                                     g_mid, ybuf, at)
                cut = theta < 1.0 - (EVENT_CUT_EDGE if event_cut else EVENT_EDGE)
                _mark_events(at, theta, forced, n, cut)
                if cut and theta * h <= 1e-14 * max(1.0, abs(t)):  # at the step's start
                    event_switch(t, ts, y, prm, sig, ptr, forced)
                    event_guards(t, ts, y, prm, sig, ptr, g_start)
                    for a in range(n):
                        forced[a] = False
                    rhs(t, ts, y, prm, sig, ptr, f0)
                    n_rhs += 1
                    jm_valid = False
                    ft_valid = False
                    o0_valid = False
                    event_cut = False
                    continue
                if cut:  # the step again, ending at the event
                    h *= theta
                    event_cut = True
                    continue
            if err <= 1.0:
                if sens is not None:
                    n_jac += _sens_step(t, t_new, ts, y, ynew, jm, e, piv,
                                        yst, prm, sig, ptr, sens, work, s)
                if j < n_out and t_out[j] <= t_new:
                    hh = t_new - t
                    if out is not None:
                        if not o0_valid:
                            outputs(t, ts, y, prm, sig, ptr, o0)
                        _output_rate(t, ts, y, f0, OUTPUT_FD * hh, prm, sig, ptr, o0, do0,
                                     ybuf, obuf)
                        outputs(t_new, ts, ynew, prm, sig, ptr, o1)
                        _output_rate(t_new, ts, ynew, f1, -OUTPUT_FD * hh, prm, sig, ptr, o1,
                                     do1, ybuf, obuf)
                    j0 = j
                    j = _dense(t, hh, y, f0, ynew, f1, o0, do0, o1, do1, t_out, j, t_stop,
                               y_out, out, slopes, prm)
                    if sens is not None:
                        _sens_dense(t, hh, t_out, j0, j, work, s, sens.s_out)
                    if out is not None:
                        for k in range(NOUT):
                            o0[k] = o1[k]
                        o0_valid = True
                else:
                    o0_valid = False
                for a in range(n):
                    y[a] = ynew[a]
                    f0[a] = f1[a]
                if sens is not None:
                    _sens_accept(work, s, jm)
                jm_valid = sens is not None
                ft_valid = False
                t = t_new
                steps += 1
                if HAS_EVENTS:
                    if event_switch(t, ts, y, prm, sig, ptr, forced):
                        rhs(t, ts, y, prm, sig, ptr, f0)
                        n_rhs += 1
                        jm_valid = False
                        o0_valid = False
                    event_guards(t, ts, y, prm, sig, ptr, g_start)
                    for a in range(n):
                        forced[a] = False
                    event_cut = False
                if dopri is None:
                    # predictive (Gustafsson) controller, as in Hairer & Wanner's RODAS
                    quot = min(5.0, max(1.0 / 6.0, err ** 0.25 / 0.9))
                    if h_acc > 0.0:
                        gus = (h_acc / h) * (err * err / err_acc) ** 0.25 / 0.9
                        quot = max(quot, min(5.0, max(1.0 / 6.0, gus)))
                    h_acc = h
                    err_acc = max(1e-2, err)
                    h_new = h / quot
                    if just_rejected:
                        h_new = min(h_new, h)
                    just_rejected = False
                    h = h_new
                else:
                    scale = 0.9 * err ** -0.2 if err > 0.0 else 5.0
                    h *= min(5.0, max(0.2, scale))
            else:
                rejected += 1
                if HAS_EVENTS:
                    event_cut = False
                    for a in range(n):
                        forced[a] = False
                if dopri is None:
                    just_rejected = True
                    h *= 0.25 if not finite else max(0.2, 0.9 * err ** -0.25)
                else:
                    h *= 0.25 if not finite else max(0.2, 0.9 * err ** -0.2)
                if h < 1e-14 * max(1.0, abs(t)):
                    status = STATUS_NON_FINITE if not finite else STATUS_STEP_UNDERFLOW
                    break
        if status != STATUS_OK:
            break
    # points beyond the last breakpoint (if any) get the final state
    while status == STATUS_OK and j < n_out:
        _write_point(t_out[j], 0.5 * (tb[-2] + tb[-1]), y, prm, sig, ptr, y_out, out, j)
        if sens is not None:
            _sens_point(s, sens.s_out, j)
        j += 1
    _finish(info, status, t, steps, rejected, n_rhs, n_jac, h)
    return y


@kernel()
def _rodas_solution(y, ks, yst, ynew, rtol, atol):
    """RODAS4's new state from its last stage (stiffly accurate) and the error norm (inf,
    False when not finite)."""
    finite = True
    for a in range(NSTATE):
        ynew[a] = yst[5, a] + ks[5, a]
        if not math.isfinite(ynew[a]):
            finite = False
    if not finite:
        return math.inf, False
    return _error_norm(ks[5], y, ynew, rtol, atol, NSTATE), True


# --------------------------------------------------------------------------- sensitivities
#: What the caller gives: the parameters' directions in the vector (CSR: pointer, slot,
#: value), the slots that occur, the initial sensitivity and the output array.
SensInput = namedtuple("SensInput", ["w_ptr", "w_idx", "w_val", "needed", "s0", "s_out"])
#: Work arrays: Jacobians at the stages (jst; jst[0] is the step's) and at the step end
#: (jend); ∂f/∂prm at one point (g); ∂f/∂θ (n × P) at the stages (gw; gw[0] at the step
#: start) and at the end (gwend); the stage increments of one parameter (dk) and its
#: stage sensitivity (sst); the sensitivity at the step end (snew) and its derivative at
#: both ends (sdot0, sdot1).
SensWork = namedtuple("SensWork", ["jst", "jend", "g", "gw", "gwend", "dk", "sst", "snew",
                                   "sdot0", "sdot1"])


@kernel()
def _sens_work(npar):
    n = NSTATE
    return SensWork(np.zeros((6, n, n)), np.zeros((n, n)), np.zeros((n, NPARAM)),
                    np.zeros((6, n, npar)), np.zeros((n, npar)), np.zeros((6, n)),
                    np.empty(n), np.empty((n, npar)), np.empty((n, npar)),
                    np.empty((n, npar)))


@kernel(inline="always")
def _jacobians(t, ts, y, prm, sig, ptr, needed, w_ptr, w_idx, w_val, g, jmat, gw):
    """At (t, y): ∂f/∂y into jmat and ∂f/∂θ (n × P) into gw: ∂f/∂prm (into g) times
    each parameter's direction in the vector (CSR: pointer, slot, value)."""
    for a in range(NSTATE):
        for b in range(NSTATE):
            jmat[a, b] = 0.0
    jac(t, ts, y, prm, sig, ptr, jmat)
    param_jac(t, ts, y, prm, sig, ptr, g, needed)
    for a in range(NSTATE):
        for p in range(gw.shape[1]):
            acc = 0.0
            for k in range(w_ptr[p], w_ptr[p + 1]):
                acc += g[a, w_idx[k]] * w_val[k]
            gw[a, p] = acc


@kernel()
def _sens_rate(jmat, gw, s, out):
    """out = J·s + ∂f/∂θ: the right-hand side of the sensitivities (n × P)."""
    for a in range(NSTATE):
        for p in range(s.shape[1]):
            acc = gw[a, p]
            for b in range(NSTATE):
                acc += jmat[a, b] * s[b, p]
            out[a, p] = acc


@kernel()
def _sens_segment(t, ts, y, prm, sig, ptr, sens, work, s):
    """At a segment start: J and ∂f/∂θ at (t, y), and the sensitivities' derivative."""
    _jacobians(t, ts, y, prm, sig, ptr, sens.needed, sens.w_ptr, sens.w_idx, sens.w_val,
               work.g, work.jend, work.gw[0])
    _sens_rate(work.jend, work.gw[0], s, work.sdot0)
    return 1


@kernel()
def _sens_step(t, t_new, ts, y, ynew, jm, e, piv, yst, prm, sig, ptr, sens, work, s):
    """Advance the sensitivities over the accepted step [t, t_new] with the stages and LU
    factors of the state: the Rosenbrock method applied to ds/dt = J(y)·s + ∂f/∂θ with
    the exact stage right-hand sides J(Y_i)·S_i + ∂f/∂θ(Y_i). As for the state's W, the
    stage coupling uses J(y) alone: the terms with second derivatives of f (∂(J·s)/∂y
    times the state's increments, and ∂(J·s + ∂f/∂θ)/∂t) are left out, which changes the
    sensitivities by far less than the 1 % the validation tier allows (tested against
    converged central differences). Returns the Jacobian count."""
    n = NSTATE
    h = t_new - t
    w_ptr, w_idx, w_val, needed = sens.w_ptr, sens.w_idx, sens.w_val, sens.needed
    for st in range(1, 6):
        _jacobians(t + STAGE_C[st] * h, ts, yst[st], prm, sig, ptr, needed, w_ptr, w_idx,
                   w_val, work.g, work.jst[st], work.gw[st])
    _jacobians(t_new, ts, ynew, prm, sig, ptr, needed, w_ptr, w_idx, w_val, work.g,
               work.jend, work.gwend)
    for a in range(n):
        for b in range(n):
            work.jst[0, a, b] = jm[a, b]
    dk = work.dk
    sst = work.sst
    inv_h = 1.0 / h
    for p in range(s.shape[1]):
        for st in range(6):
            for a in range(n):
                acc = s[a, p]
                for jj in range(st):
                    acc += STAGE_A[st, jj] * dk[jj, a]
                sst[a] = acc
            for a in range(n):
                acc = work.gw[st, a, p]
                for b in range(n):
                    acc += work.jst[st, a, b] * sst[b]
                for jj in range(st):
                    acc += STAGE_G[st, jj] * inv_h * dk[jj, a]
                dk[st, a] = acc
            lu_solve(e, piv, dk[st], n)
        for a in range(n):
            work.snew[a, p] = sst[a] + dk[5, a]
    _sens_rate(work.jend, work.gwend, work.snew, work.sdot1)
    return 7


@kernel()
def _sens_dense(t, h, t_out, j0, j1, work, s, s_out):
    for jj in range(j0, j1):
        h00, h10, h01, h11 = _hermite((t_out[jj] - t) / h)
        for a in range(NSTATE):
            for p in range(s.shape[1]):
                s_out[a, jj, p] = (h00 * s[a, p] + h10 * h * work.sdot0[a, p]
                                   + h01 * work.snew[a, p] + h11 * h * work.sdot1[a, p])


@kernel()
def _sens_accept(work, s, jm):
    """The step is taken: its end becomes the next step's start (s, ṡ, J, ∂f/∂θ)."""
    for a in range(NSTATE):
        for p in range(s.shape[1]):
            s[a, p] = work.snew[a, p]
            work.sdot0[a, p] = work.sdot1[a, p]
            work.gw[0, a, p] = work.gwend[a, p]
        for b in range(NSTATE):
            jm[a, b] = work.jend[a, b]


@kernel()
def _sens_jump(t, ts, y, prm, sig, ptr, sens, s):
    """The sensitivities across a jump y⁺ = jump(y⁻, θ): s⁺ = ∂jump/∂y·s⁻ + ∂jump/∂θ, by
    central differences of the compiled ``jump`` along each parameter's direction (the
    state moved by ±ε·s, the vector by ±ε·w). A state the jump leaves alone keeps its
    sensitivity exactly."""
    n = NSTATE
    yp = np.empty(n)
    ym = np.empty(n)
    up = prm.copy()
    down = prm.copy()
    w_ptr, w_idx, w_val = sens.w_ptr, sens.w_idx, sens.w_val
    for p in range(s.shape[1]):
        scale = 0.0
        for k in range(w_ptr[p], w_ptr[p + 1]):
            scale = max(scale, abs(prm[w_idx[k]]))
        eps = JUMP_FD * (scale if scale > 0.0 else 1.0)
        for k in range(w_ptr[p], w_ptr[p + 1]):
            up[w_idx[k]] = prm[w_idx[k]] + eps * w_val[k]
            down[w_idx[k]] = prm[w_idx[k]] - eps * w_val[k]
        for a in range(n):
            yp[a] = y[a] + eps * s[a, p]
            ym[a] = y[a] - eps * s[a, p]
        jump(t, ts, yp, up, sig, ptr)
        jump(t, ts, ym, down, sig, ptr)
        for a in range(n):
            if yp[a] != y[a] + eps * s[a, p] or ym[a] != y[a] - eps * s[a, p]:
                s[a, p] = (yp[a] - ym[a]) / (2.0 * eps)
        for k in range(w_ptr[p], w_ptr[p + 1]):
            up[w_idx[k]] = prm[w_idx[k]]
            down[w_idx[k]] = prm[w_idx[k]]


@kernel()
def _sens_point(s, s_out, j):
    for a in range(NSTATE):
        for p in range(s.shape[1]):
            s_out[a, j, p] = s[a, p]


@kernel()
def output_sensitivities(t_out, ts_out, y_out, s_out, prm, sig, ptr, w_ptr, w_idx, w_val,
                         res):
    """d(output)/dθ = ∂out/∂y·s + ∂out/∂θ at each output time (res: NOUT × n_out × P),
    by directional differences (a parameter moves the vector along its column of W)."""
    n_out = t_out.shape[0]
    derive(prm)
    base = np.empty(NOUT)
    pert = np.empty(NOUT)
    ybuf = np.empty(NSTATE)
    for p in range(w_ptr.shape[0] - 1):
        prm_p = prm.copy()
        scale = 0.0
        for k in range(w_ptr[p], w_ptr[p + 1]):
            scale = max(scale, abs(prm[w_idx[k]]))
        eps = 1e-7 * (scale if scale > 0.0 else 1.0)
        for k in range(w_ptr[p], w_ptr[p + 1]):
            prm_p[w_idx[k]] += eps * w_val[k]
        for jj in range(n_out):
            outputs(t_out[jj], ts_out[jj], y_out[jj], prm, sig, ptr, base)
            for a in range(NSTATE):
                ybuf[a] = y_out[jj, a] + eps * s_out[a, jj, p]
            outputs(t_out[jj], ts_out[jj], ybuf, prm_p, sig, ptr, pert)
            for k in range(NOUT):
                res[k, jj, p] = (pert[k] - base[k]) / eps


# --------------------------------------------------------------------------- Dormand-Prince
B21 = 1.0 / 5.0
B31, B32 = 3.0 / 40.0, 9.0 / 40.0
B41, B42, B43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
B51, B52, B53, B54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
B61, B62, B63 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0
B64, B65 = 49.0 / 176.0, -5103.0 / 18656.0
W1, W3, W4, W5, W6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
E1, E3, E4 = 71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0
E5, E6, E7 = -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0
DP_A = np.array([[0.0, 0.0, 0.0, 0.0, 0.0], [B21, 0.0, 0.0, 0.0, 0.0],
                 [B31, B32, 0.0, 0.0, 0.0], [B41, B42, B43, 0.0, 0.0],
                 [B51, B52, B53, B54, 0.0], [B61, B62, B63, B64, B65]])
DP_C = np.array([0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0])
DP_W = np.array([W1, 0.0, W3, W4, W5, W6])
DP_E = np.array([E1, 0.0, E3, E4, E5, E6])


@kernel()
def _dopri_stages(t, h, ts, y, prm, sig, ptr, ks, cont):
    """Stages 2..6 of one Dormand-Prince step (ks[0] holds f(t, y))."""
    n = NSTATE
    for st in range(1, 6):
        for a in range(n):
            acc = 0.0
            for jj in range(st):
                acc += DP_A[st, jj] * ks[jj, a]
            cont[a] = y[a] + h * acc
        rhs(t + DP_C[st] * h, ts, cont, prm, sig, ptr, ks[st])
