"""Kernel template: the compiled integrators, joined to one model by the generator.

``integrate_rodas4``: Hairer & Wanner's RODAS (order 4, embedded 3), a 6-stage,
L-stable, stiffly accurate Rosenbrock method with the model's analytic Jacobian; the
default. ``integrate_dopri5``: Dormand-Prince 5(4), explicit, for non-stiff variants.

Both integrate interval by interval between breakpoints (corners and jumps of the
inputs), control the step on a per-state rtol/atol, and write the states and the model's
derived outputs at the requested times by cubic Hermite interpolation of each step
(dense output). They never raise: ``info`` reports the status, where and how it failed.
"""

import math

import numpy as np
from numba import njit

from pneumact.models.layout import I_GAMMA, I_R, I_RLIN, I_T
from pneumact.models.pneumatics import derive_flow_constants
from pneumact.simulation.linalg import lu_factor, lu_solve

# isort: off
# --- components ---
from pneumact.simulation.templates.actuator import (
    NOUT,
    NSTATE,
    friction_param_rhs,
    jac,
    outputs,
    rhs,
)

# --- end components ---
# isort: on

STATUS_OK = 0
STATUS_STEP_UNDERFLOW = 1
STATUS_NON_FINITE = 2
STATUS_MAX_STEPS = 3
# info layout
INFO_STATUS = 0
INFO_T = 1
INFO_STEPS = 2
INFO_REJECTED = 3
INFO_RHS = 4
INFO_JAC = 5
INFO_H = 6
INFO_LENGTH = 8

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


@njit(cache=True, inline="always")
def _error_norm(err, y, ynew, rtol, atol, n):  # pragma: no cover - compiled
    s = 0.0
    for i in range(n):
        sc = atol[i] + rtol * max(abs(y[i]), abs(ynew[i]))
        e = err[i] / sc
        s += e * e
    return math.sqrt(s / n)


@njit(cache=True)
def _dense(t0, h, y0, f0, y1, f1, t_out, j, ts, prm, sig, ptr, y_out, out, ybuf, obuf,
           t_stop):  # pragma: no cover - compiled
    """Write every requested time in (t0, t0 + h] (and ≤ t_stop) by Hermite cubics."""
    n_out = t_out.shape[0]
    while j < n_out and t_out[j] <= t_stop and t_out[j] <= t0 + h:
        th = (t_out[j] - t0) / h
        h00 = (1.0 + 2.0 * th) * (1.0 - th) ** 2
        h10 = th * (1.0 - th) ** 2
        h01 = th * th * (3.0 - 2.0 * th)
        h11 = th * th * (th - 1.0)
        for i in range(NSTATE):
            ybuf[i] = h00 * y0[i] + h10 * h * f0[i] + h01 * y1[i] + h11 * h * f1[i]
            y_out[j, i] = ybuf[i]
        outputs(t_out[j], ts, ybuf, prm, sig, ptr, obuf)
        for i in range(NOUT):
            out[j, i] = obuf[i]
        j += 1
    return j


@njit(cache=True)
def _write_point(t, ts, y, prm, sig, ptr, j, y_out, out, obuf):  # pragma: no cover
    for i in range(NSTATE):
        y_out[j, i] = y[i]
    outputs(t, ts, y, prm, sig, ptr, obuf)
    for i in range(NOUT):
        out[j, i] = obuf[i]


@njit(cache=True)
def _enters_flow_constants(i):  # pragma: no cover - compiled
    """Whether parameter slot ``i`` changes the derived orifice-flow constants."""
    return i == I_GAMMA or i == I_R or i == I_T or i == I_RLIN


@njit(cache=True, inline="always")
def _directional(t, ts, y, dy, prm, prm_p, eps, f_base, sig, ptr, ybuf, fbuf, q, n,
                 flow_parameter):
    """(f(t, y + eps·dy, θ + eps·e_j) − f_base)/eps: J·dy + ∂f/∂θ_j in one evaluation."""
    for a in range(n):
        ybuf[a] = y[a] + eps * dy[a]
    if flow_parameter:
        derive_flow_constants(prm_p)
    rhs(t, ts, ybuf, prm_p, sig, ptr, fbuf)
    for a in range(n):
        q[a] = (fbuf[a] - f_base[a]) / eps


@njit(cache=True, nogil=True)
def integrate_rodas4(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps,
                     y_out, out, info):  # pragma: no cover - compiled
    """Integrate from tb[0] to tb[-1]; return the final state (the failing one on error)."""
    no_index = np.zeros(0, dtype=np.int64)
    return integrate_rodas4_sens(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max,
                                 max_steps, y_out, out, info, no_index, no_index,
                                 np.zeros((NSTATE, 0)), np.zeros((0, NSTATE, 0)))


@njit(cache=True, nogil=True)
def integrate_rodas4_sens(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max,
                          max_steps, y_out, out, info, pidx, pfast, s0,
                          s_out):  # pragma: no cover - compiled
    """RODAS4 with forward sensitivities dy/dθ for the parameters ``prm[pidx]``.

    The sensitivities obey ṡ = J·s + ∂f/∂θ. They are advanced with the same stages and
    the same LU factors as the state (the staggered direct method); each stage needs one
    directional difference of the model, J(Y_i)·dY_i + ∂f/∂θ_j, in one evaluation.
    Error control is on the states only. ``s0`` (n × P) is the initial sensitivity,
    ``s_out`` (n_out × n × P) receives them at ``t_out``. Parameters with
    ``pfast[j] = k >= 0`` are the friction parameter FRICTION_SENS[k]: for them the stage
    right-hand side is J(Y_i)·dY_i + ∂f/∂θ_k from the analytic Jacobian and the analytic
    friction derivatives, shared by all of them (one Jacobian per stage).
    """
    n = NSTATE
    npar = pidx.shape[0]
    derive_flow_constants(prm)
    y = y0.copy()
    ynew = np.empty(n)
    f0 = np.empty(n)
    f1 = np.empty(n)
    fb = np.empty(n)
    fbt = np.empty(n)
    ft = np.empty(n)
    cont = np.empty(n)
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    k5 = np.empty(n)
    k6 = np.empty(n)
    fst = np.empty((6, n))
    yst = np.empty((6, n))
    jm = np.zeros((n, n))
    e = np.empty((n, n))
    piv = np.zeros(n, dtype=np.int64)
    ybuf = np.empty(n)
    obuf = np.empty(NOUT)
    # sensitivity work arrays
    sens = s0.copy()
    snew = np.empty((n, npar))
    sdot0 = np.empty((n, npar))
    sdot1 = np.empty((n, npar))
    dk = np.empty((6, n))
    dy = np.empty(n)
    q = np.empty(n)
    qt = np.empty(n)
    sft = np.empty(n)
    fbuf = np.empty(n)
    ybuf2 = np.empty(n)
    prm_p = prm.copy()
    nfast = 0
    for p_ in range(npar):
        if pfast[p_] >= 0:
            nfast += 1
    jst = np.zeros((6, n, n))
    gst = np.zeros((6, 6, n))
    jt = np.zeros((n, n))
    jend = np.zeros((n, n))
    gend = np.zeros((6, n))
    dwork = np.zeros((6, 2))
    eps_p = np.empty(npar)
    for p_ in range(npar):
        scale = abs(prm[pidx[p_]])
        eps_p[p_] = 1e-7 * (scale if scale > 0.0 else 1.0)
    for i in range(INFO_LENGTH):
        info[i] = 0.0
    n_out = t_out.shape[0]
    h = h_init
    steps = 0
    rejected = 0
    n_rhs = 0
    n_jac = 0
    j = 0
    t = tb[0]
    ts0 = 0.5 * (tb[0] + tb[1])
    while j < n_out and t_out[j] <= t:
        _write_point(t, ts0, y, prm, sig, ptr, j, y_out, out, obuf)
        for a in range(n):
            for p_ in range(npar):
                s_out[j, a, p_] = sens[a, p_]
        j += 1
    status = STATUS_OK
    last_nonfinite = False
    just_rejected = False
    h_acc = 0.0
    err_acc = 1.0
    for seg in range(tb.shape[0] - 1):
        t = tb[seg]
        t_end = tb[seg + 1]
        if t_end <= t:
            continue
        ts = 0.5 * (t + t_end)
        dts = max(1e-9, 1e-6 * (t_end - t))
        jm_valid = False
        ft_valid = False
        rhs(t, ts, y, prm, sig, ptr, f0)
        n_rhs += 1
        for p_ in range(npar):
            flowp = _enters_flow_constants(pidx[p_])
            prm_p[pidx[p_]] = prm[pidx[p_]] + eps_p[p_]
            _directional(t, ts, y, sens[:, p_], prm, prm_p, eps_p[p_], f0, sig, ptr, ybuf2,
                         fbuf, q, n, flowp)
            prm_p[pidx[p_]] = prm[pidx[p_]]
            if flowp:
                derive_flow_constants(prm_p)
            for a in range(n):
                sdot0[a, p_] = q[a]
        while t < t_end:
            if steps >= max_steps:
                status = STATUS_MAX_STEPS
                break
            h = min(h, h_max)
            last = False
            if t + h >= t_end - 1e-3 * h:
                h = t_end - t
                last = True
            # Jacobian and time derivative (forward difference inside the segment); both
            # are kept after a rejected step (same t, y), and the Jacobian at the end of
            # an accepted step is reused when the sensitivity pass computed it
            if not jm_valid:
                for a in range(n):
                    for b in range(n):
                        jm[a, b] = 0.0
                jac(t, ts, y, prm, sig, ptr, jm)
                n_jac += 1
            if not ft_valid:
                dt = 1.4901161193847656e-08 * max(abs(t), 1e-3)
                rhs(t + dt, ts, y, prm, sig, ptr, fb)
                n_rhs += 1
                for a in range(n):
                    ft[a] = (fb[a] - f0[a]) / dt
            jm_valid = True
            ft_valid = True
            fac = 1.0 / (h * GAM)
            for a in range(n):
                for b in range(n):
                    e[a, b] = -jm[a, b]
                e[a, a] += fac
            if not lu_factor(e, piv, n):
                h *= 0.5
                rejected += 1
                if h < 1e-14 * max(1.0, abs(t)):
                    status = STATUS_STEP_UNDERFLOW
                    break
                continue
            # stage 1
            for a in range(n):
                k1[a] = f0[a] + h * D1 * ft[a]
                yst[0, a] = y[a]
                fst[0, a] = f0[a]
            lu_solve(e, piv, k1, n)
            # stage 2
            for a in range(n):
                cont[a] = y[a] + A21 * k1[a]
            rhs(t + C2 * h, ts, cont, prm, sig, ptr, fb)
            for a in range(n):
                yst[1, a] = cont[a]
                fst[1, a] = fb[a]
                k2[a] = fb[a] + G21 / h * k1[a] + h * D2 * ft[a]
            lu_solve(e, piv, k2, n)
            # stage 3
            for a in range(n):
                cont[a] = y[a] + A31 * k1[a] + A32 * k2[a]
            rhs(t + C3 * h, ts, cont, prm, sig, ptr, fb)
            for a in range(n):
                yst[2, a] = cont[a]
                fst[2, a] = fb[a]
                k3[a] = fb[a] + (G31 * k1[a] + G32 * k2[a]) / h + h * D3 * ft[a]
            lu_solve(e, piv, k3, n)
            # stage 4
            for a in range(n):
                cont[a] = y[a] + A41 * k1[a] + A42 * k2[a] + A43 * k3[a]
            rhs(t + C4 * h, ts, cont, prm, sig, ptr, fb)
            for a in range(n):
                yst[3, a] = cont[a]
                fst[3, a] = fb[a]
                k4[a] = fb[a] + (G41 * k1[a] + G42 * k2[a] + G43 * k3[a]) / h + h * D4 * ft[a]
            lu_solve(e, piv, k4, n)
            # stage 5
            for a in range(n):
                cont[a] = y[a] + A51 * k1[a] + A52 * k2[a] + A53 * k3[a] + A54 * k4[a]
            rhs(t + h, ts, cont, prm, sig, ptr, fb)
            for a in range(n):
                yst[4, a] = cont[a]
                fst[4, a] = fb[a]
                k5[a] = fb[a] + (G51 * k1[a] + G52 * k2[a] + G53 * k3[a] + G54 * k4[a]) / h
            lu_solve(e, piv, k5, n)
            # stage 6 (stiffly accurate: the solution is the last stage value)
            for a in range(n):
                cont[a] += k5[a]
            rhs(t + h, ts, cont, prm, sig, ptr, fb)
            for a in range(n):
                yst[5, a] = cont[a]
                fst[5, a] = fb[a]
                k6[a] = fb[a] + (G61 * k1[a] + G62 * k2[a] + G63 * k3[a] + G64 * k4[a]
                                 + G65 * k5[a]) / h
            lu_solve(e, piv, k6, n)
            n_rhs += 5
            finite = True
            for a in range(n):
                ynew[a] = cont[a] + k6[a]
                if not math.isfinite(ynew[a]):
                    finite = False
            err = _error_norm(k6, y, ynew, rtol, atol, n) if finite else math.inf
            if err <= 1.0:
                t_new = t_end if last else t + h
                rhs(t_new, ts, ynew, prm, sig, ptr, f1)
                n_rhs += 1
                if npar > nfast:
                    rhs(t + dts, ts, y, prm, sig, ptr, fbt)
                    n_rhs += 1
                if nfast > 0:
                    # shared by the fast parameters: Jacobians and ∂f/∂θ at the stages
                    for st in range(6):
                        tc = t + (0.0 if st == 0 else C2 * h if st == 1 else C3 * h if st == 2
                                  else C4 * h if st == 3 else h)
                        for a in range(n):
                            for b in range(n):
                                jst[st, a, b] = jm[a, b] if st == 0 else 0.0
                        if st > 0:
                            jac(tc, ts, yst[st], prm, sig, ptr, jst[st])
                        friction_param_rhs(tc, ts, yst[st], prm, sig, ptr, dwork, gst[st])
                    for a in range(n):
                        for b in range(n):
                            jt[a, b] = 0.0
                            jend[a, b] = 0.0
                    jac(t + dts, ts, y, prm, sig, ptr, jt)
                    jac(t_new, ts, ynew, prm, sig, ptr, jend)
                    friction_param_rhs(t_new, ts, ynew, prm, sig, ptr, dwork, gend)
                    n_jac += 7
                for p_ in range(npar):
                    pi = pidx[p_]
                    kf = pfast[p_]
                    flowp = _enters_flow_constants(pi)
                    prm_p[pi] = prm[pi] + eps_p[p_]
                    ep = eps_p[p_]
                    # time derivative of the sensitivity right-hand side (mixed difference)
                    if kf >= 0:
                        # (J(t + dts) − J(t))·s/dts; friction terms have no explicit t
                        for a in range(n):
                            acc = 0.0
                            for b in range(n):
                                acc += (jt[a, b] - jm[a, b]) * sens[b, p_]
                            sft[a] = acc / dts
                    else:
                        for a in range(n):
                            dy[a] = sens[a, p_]
                        _directional(t + dts, ts, y, dy, prm, prm_p, ep, fbt, sig, ptr, ybuf2,
                                     fbuf, qt, n, flowp)
                        for a in range(n):
                            sft[a] = (qt[a] - sdot0[a, p_]) / dts
                    for st in range(6):
                        # stage sensitivity dY_st
                        for a in range(n):
                            if st == 0:
                                dy[a] = sens[a, p_]
                            elif st == 1:
                                dy[a] = sens[a, p_] + A21 * dk[0, a]
                            elif st == 2:
                                dy[a] = sens[a, p_] + A31 * dk[0, a] + A32 * dk[1, a]
                            elif st == 3:
                                dy[a] = (sens[a, p_] + A41 * dk[0, a] + A42 * dk[1, a]
                                         + A43 * dk[2, a])
                            elif st == 4:
                                dy[a] = (sens[a, p_] + A51 * dk[0, a] + A52 * dk[1, a]
                                         + A53 * dk[2, a] + A54 * dk[3, a])
                            else:
                                dy[a] = (sens[a, p_] + A51 * dk[0, a] + A52 * dk[1, a]
                                         + A53 * dk[2, a] + A54 * dk[3, a] + dk[4, a])
                        if st == 0:
                            for a in range(n):
                                q[a] = sdot0[a, p_]
                        elif kf >= 0:
                            for a in range(n):
                                acc = gst[st, kf, a]
                                for b in range(n):
                                    acc += jst[st, a, b] * dy[b]
                                q[a] = acc
                        else:
                            tc = t + (C2 * h if st == 1 else C3 * h if st == 2 else
                                      C4 * h if st == 3 else h)
                            _directional(tc, ts, yst[st], dy, prm, prm_p, ep, fst[st], sig,
                                         ptr, ybuf2, fbuf, q, n, flowp)
                        for a in range(n):
                            if st == 0:
                                r = q[a] + h * D1 * sft[a]
                            elif st == 1:
                                r = q[a] + G21 / h * dk[0, a] + h * D2 * sft[a]
                            elif st == 2:
                                r = q[a] + (G31 * dk[0, a] + G32 * dk[1, a]) / h + h * D3 * sft[a]
                            elif st == 3:
                                r = (q[a] + (G41 * dk[0, a] + G42 * dk[1, a] + G43 * dk[2, a]) / h
                                     + h * D4 * sft[a])
                            elif st == 4:
                                r = q[a] + (G51 * dk[0, a] + G52 * dk[1, a] + G53 * dk[2, a]
                                            + G54 * dk[3, a]) / h
                            else:
                                r = q[a] + (G61 * dk[0, a] + G62 * dk[1, a] + G63 * dk[2, a]
                                            + G64 * dk[3, a] + G65 * dk[4, a]) / h
                            dk[st, a] = r
                        lu_solve(e, piv, dk[st], n)
                    for a in range(n):
                        snew[a, p_] = dy[a] + dk[5, a]
                    # derivative at the step end, for the dense output of the sensitivities
                    if kf >= 0:
                        for a in range(n):
                            acc = gend[kf, a]
                            for b in range(n):
                                acc += jend[a, b] * snew[b, p_]
                            sdot1[a, p_] = acc
                    else:
                        for a in range(n):
                            dy[a] = snew[a, p_]
                        _directional(t_new, ts, ynew, dy, prm, prm_p, ep, f1, sig, ptr, ybuf2,
                                     fbuf, q, n, flowp)
                        for a in range(n):
                            sdot1[a, p_] = q[a]
                        n_rhs += 7
                    prm_p[pi] = prm[pi]
                    if flowp:
                        derive_flow_constants(prm_p)
                j0 = j
                j = _dense(t, t_new - t, y, f0, ynew, f1, t_out, j, ts, prm, sig, ptr, y_out,
                           out, ybuf, obuf, t_end)
                if npar > 0:
                    hh = t_new - t
                    for jj in range(j0, j):
                        th = (t_out[jj] - t) / hh
                        h00 = (1.0 + 2.0 * th) * (1.0 - th) ** 2
                        h10 = th * (1.0 - th) ** 2
                        h01 = th * th * (3.0 - 2.0 * th)
                        h11 = th * th * (th - 1.0)
                        for a in range(n):
                            for p_ in range(npar):
                                s_out[jj, a, p_] = (h00 * sens[a, p_] + h10 * hh * sdot0[a, p_]
                                                    + h01 * snew[a, p_]
                                                    + h11 * hh * sdot1[a, p_])
                for a in range(n):
                    y[a] = ynew[a]
                    f0[a] = f1[a]
                    for p_ in range(npar):
                        sens[a, p_] = snew[a, p_]
                        sdot0[a, p_] = sdot1[a, p_]
                    if nfast > 0:
                        for b in range(n):
                            jm[a, b] = jend[a, b]
                jm_valid = nfast > 0
                ft_valid = False
                t = t_new
                steps += 1
                last_nonfinite = False
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
                rejected += 1
                just_rejected = True
                last_nonfinite = not finite
                h *= 0.25 if not finite else max(0.2, 0.9 * err ** -0.25)
                if h < 1e-14 * max(1.0, abs(t)):
                    status = STATUS_NON_FINITE if last_nonfinite else STATUS_STEP_UNDERFLOW
                    break
        if status != STATUS_OK:
            break
    # points beyond the last breakpoint (if any) get the final state
    while status == STATUS_OK and j < n_out:
        _write_point(t_out[j], 0.5 * (tb[-2] + tb[-1]), y, prm, sig, ptr, j, y_out, out, obuf)
        for a in range(n):
            for p_ in range(npar):
                s_out[j, a, p_] = sens[a, p_]
        j += 1
    info[INFO_STATUS] = status
    info[INFO_T] = t
    info[INFO_STEPS] = steps
    info[INFO_REJECTED] = rejected
    info[INFO_RHS] = n_rhs
    info[INFO_JAC] = n_jac
    info[INFO_H] = h
    return y


# Dormand-Prince 5(4)
B21 = 1.0 / 5.0
B31, B32 = 3.0 / 40.0, 9.0 / 40.0
B41, B42, B43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
B51, B52, B53, B54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
B61, B62, B63 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0
B64, B65 = 49.0 / 176.0, -5103.0 / 18656.0
W1, W3, W4, W5, W6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
E1, E3, E4 = 71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0
E5, E6, E7 = -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0


@njit(cache=True, nogil=True)
def integrate_dopri5(y0, prm, sig, ptr, tb, t_out, rtol, atol, h_init, h_max, max_steps,
                     y_out, out, info):  # pragma: no cover - compiled
    """Explicit adaptive Dormand-Prince 5(4); same interface as ``integrate_rodas4``."""
    n = NSTATE
    derive_flow_constants(prm)
    y = y0.copy()
    ynew = np.empty(n)
    cont = np.empty(n)
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    k5 = np.empty(n)
    k6 = np.empty(n)
    k7 = np.empty(n)
    err = np.empty(n)
    ybuf = np.empty(n)
    obuf = np.empty(NOUT)
    for i in range(INFO_LENGTH):
        info[i] = 0.0
    n_out = t_out.shape[0]
    h = h_init
    steps = 0
    rejected = 0
    n_rhs = 0
    j = 0
    t = tb[0]
    ts0 = 0.5 * (tb[0] + tb[1])
    while j < n_out and t_out[j] <= t:
        _write_point(t, ts0, y, prm, sig, ptr, j, y_out, out, obuf)
        j += 1
    status = STATUS_OK
    for seg in range(tb.shape[0] - 1):
        t = tb[seg]
        t_end = tb[seg + 1]
        if t_end <= t:
            continue
        ts = 0.5 * (t + t_end)
        rhs(t, ts, y, prm, sig, ptr, k1)
        n_rhs += 1
        while t < t_end:
            if steps >= max_steps:
                status = STATUS_MAX_STEPS
                break
            h = min(h, h_max)
            last = False
            if t + h >= t_end - 1e-3 * h:
                h = t_end - t
                last = True
            for a in range(n):
                cont[a] = y[a] + h * B21 * k1[a]
            rhs(t + 0.2 * h, ts, cont, prm, sig, ptr, k2)
            for a in range(n):
                cont[a] = y[a] + h * (B31 * k1[a] + B32 * k2[a])
            rhs(t + 0.3 * h, ts, cont, prm, sig, ptr, k3)
            for a in range(n):
                cont[a] = y[a] + h * (B41 * k1[a] + B42 * k2[a] + B43 * k3[a])
            rhs(t + 0.8 * h, ts, cont, prm, sig, ptr, k4)
            for a in range(n):
                cont[a] = y[a] + h * (B51 * k1[a] + B52 * k2[a] + B53 * k3[a] + B54 * k4[a])
            rhs(t + 8.0 / 9.0 * h, ts, cont, prm, sig, ptr, k5)
            for a in range(n):
                cont[a] = y[a] + h * (B61 * k1[a] + B62 * k2[a] + B63 * k3[a] + B64 * k4[a]
                                      + B65 * k5[a])
            rhs(t + h, ts, cont, prm, sig, ptr, k6)
            finite = True
            for a in range(n):
                ynew[a] = y[a] + h * (W1 * k1[a] + W3 * k3[a] + W4 * k4[a] + W5 * k5[a]
                                      + W6 * k6[a])
                if not math.isfinite(ynew[a]):
                    finite = False
            t_new = t_end if last else t + h
            if finite:
                rhs(t_new, ts, ynew, prm, sig, ptr, k7)
            n_rhs += 6
            if finite:
                for a in range(n):
                    err[a] = h * (E1 * k1[a] + E3 * k3[a] + E4 * k4[a] + E5 * k5[a]
                                  + E6 * k6[a] + E7 * k7[a])
                en = _error_norm(err, y, ynew, rtol, atol, n)
            else:
                en = math.inf
            if en <= 1.0:
                j = _dense(t, t_new - t, y, k1, ynew, k7, t_out, j, ts, prm, sig, ptr, y_out,
                           out, ybuf, obuf, t_end)
                for a in range(n):
                    y[a] = ynew[a]
                    k1[a] = k7[a]
                t = t_new
                steps += 1
                scale = 0.9 * en ** -0.2 if en > 0.0 else 5.0
                h *= min(5.0, max(0.2, scale))
            else:
                rejected += 1
                h *= 0.25 if not finite else max(0.2, 0.9 * en ** -0.2)
                if h < 1e-14 * max(1.0, abs(t)):
                    status = STATUS_NON_FINITE if not finite else STATUS_STEP_UNDERFLOW
                    break
        if status != STATUS_OK:
            break
    while status == STATUS_OK and j < n_out:
        _write_point(t_out[j], 0.5 * (tb[-2] + tb[-1]), y, prm, sig, ptr, j, y_out, out, obuf)
        j += 1
    info[INFO_STATUS] = status
    info[INFO_T] = t
    info[INFO_STEPS] = steps
    info[INFO_REJECTED] = rejected
    info[INFO_RHS] = n_rhs
    info[INFO_JAC] = 0
    info[INFO_H] = h
    return y


@njit(cache=True)
def output_sensitivities(t_out, ts_out, y_out, s_out, prm, pidx, sig, ptr,
                         res):  # pragma: no cover - compiled
    """d(output)/dθ = ∂out/∂y·s + ∂out/∂θ at each output time, by directional differences."""
    n_out = t_out.shape[0]
    npar = pidx.shape[0]
    derive_flow_constants(prm)
    base = np.empty(NOUT)
    pert = np.empty(NOUT)
    ybuf = np.empty(NSTATE)
    prm_p = prm.copy()
    for jj in range(n_out):
        outputs(t_out[jj], ts_out[jj], y_out[jj], prm, sig, ptr, base)
        for p_ in range(npar):
            pi = pidx[p_]
            scale = abs(prm[pi])
            ep = 1e-7 * (scale if scale > 0.0 else 1.0)
            prm_p[pi] = prm[pi] + ep
            if _enters_flow_constants(pi):
                derive_flow_constants(prm_p)
            for a in range(NSTATE):
                ybuf[a] = y_out[jj, a] + ep * s_out[jj, a, p_]
            outputs(t_out[jj], ts_out[jj], ybuf, prm_p, sig, ptr, pert)
            for k in range(NOUT):
                res[jj, k, p_] = (pert[k] - base[k]) / ep
            prm_p[pi] = prm[pi]
            if _enters_flow_constants(pi):
                derive_flow_constants(prm_p)
