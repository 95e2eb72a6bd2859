"""Kernel template: the generalized Maxwell-slip law on its slice of the state vector
(N block deflections, then their N modes; ``models.friction.gms``), and the two
model-level functions the integrator calls at its events: ``event_guards`` (one guard per
block, > 0 while the block keeps its mode) and ``event_switch`` (switch the blocks whose
guard reached 0).

N is read off the law's block, (FRICTION_HI − FRICTION_LO − GMS_COMMON) / 2: a constant
of the compiled module. The rates and partials depend on every block, so the functions
that store them compute them from (v, y, p, o), which the value returned to the
template carries.
"""

from pneumact.core import kernel
from pneumact.models.friction.base import (
    RELAXED_LEVEL,
    presliding_scale,
    sign,
    stribeck_curve,
    stribeck_curve_params,
)
from pneumact.models.friction.gms import (
    GMS_C,
    GMS_COMMON,
    GMS_DELTA,
    GMS_FC,
    GMS_FS,
    GMS_SIGMA1,
    GMS_SIGMA2,
    GMS_VS,
    element_rate,
    guard,
    share_sum,
)

# --- bound by the generator --------------------------------------------------------------
FRICTION_LO = FRICTION_HI = 0
S_FRICTION = 0
#: the model's velocity at (t, y): its state, or a kinematic drive's (the model template's)
model_velocity = None
#: the law on its own (``law_alone``) has no velocity and calls no event function
OPTIONAL_FUNCTIONS = ("model_velocity",)
# ------------------------------------------------------------------------------------------


@kernel(inline="always")
def _blocks():
    return (FRICTION_HI - FRICTION_LO - GMS_COMMON) // 2


@kernel(inline="always")
def _level(v, p, o):
    """g(v), dg/dv, and whether the blocks carry force at all (g above the relaxed level:
    without friction they rest at z = 0, as LuGre's bristle does)."""
    level, slope = stribeck_curve(v, p[o + GMS_FC], p[o + GMS_FS], p[o + GMS_VS],
                                  p[o + GMS_DELTA])
    return level, slope, level > RELAXED_LEVEL * p[o + GMS_FS]


@kernel()
def _block_rate(v, y, s, p, o, i, n, level, live):
    """(ż, ∂ż/∂g, ∂ż/∂z) of block i."""
    if not live:
        return 0.0, 0.0, 0.0
    return element_rate(v, y[s + i], y[s + n + i], p[o + GMS_COMMON + i], p[o + GMS_C],
                        p[o + GMS_COMMON + n + i] / share_sum(p, o, n), level)


@kernel(inline="always")
def _velocity_partial(mode, dzd_dg, slope, live):
    """∂ż/∂v of a block: 1 while it is stuck (and the law carries force), through g(v)
    while it slips."""
    if mode == 0.0:
        return 1.0 if live else 0.0
    return dzd_dg * slope


@kernel()
def _total_stiffness(p, o, n):
    total = 0.0
    for i in range(n):
        total += p[o + GMS_COMMON + i]
    return total


@kernel()
def friction_force(v, y, s, p, o):
    n = _blocks()
    level, _, live = _level(v, p, o)
    spring = 0.0
    damping = 0.0
    for i in range(n):
        k = p[o + GMS_COMMON + i]
        spring += k * y[s + i]
        damping += k * _block_rate(v, y, s, p, o, i, n, level, live)[0]
    return spring + p[o + GMS_SIGMA1] * damping / _total_stiffness(p, o, n) + p[
        o + GMS_SIGMA2] * v


@kernel(inline="always")
def friction_rates(v, y, s, p, o):
    return friction_force(v, y, s, p, o), (v, y, p, o)


@kernel()
def friction_store(rates, dydt, s):
    v, y, p, o = rates
    n = _blocks()
    level, _, live = _level(v, p, o)
    for i in range(n):
        dydt[s + i] = _block_rate(v, y, s, p, o, i, n, level, live)[0]
        dydt[s + n + i] = 0.0


@kernel()
def friction_partials(v, y, s, p, o):
    n = _blocks()
    level, slope, live = _level(v, p, o)
    damping = 0.0
    for i in range(n):
        _, dzd_dg, _ = _block_rate(v, y, s, p, o, i, n, level, live)
        damping += p[o + GMS_COMMON + i] * _velocity_partial(y[s + n + i], dzd_dg, slope,
                                                             live)
    df_dv = p[o + GMS_SIGMA1] * damping / _total_stiffness(p, o, n) + p[o + GMS_SIGMA2]
    return friction_force(v, y, s, p, o), df_dv, (v, y, p, o)


@kernel()
def friction_store_partials(partials, jac, s, col_v, row_f, mass):
    v, y, p, o = partials
    n = _blocks()
    level, slope, live = _level(v, p, o)
    damping_per_stiffness = p[o + GMS_SIGMA1] / _total_stiffness(p, o, n)
    for i in range(n):
        _, dzd_dg, dzd_dz = _block_rate(v, y, s, p, o, i, n, level, live)
        jac[s + i, s + i] = dzd_dz
        if col_v >= 0:
            jac[s + i, col_v] = _velocity_partial(y[s + n + i], dzd_dg, slope, live)
        if row_f >= 0:
            k = p[o + GMS_COMMON + i]
            jac[row_f, s + i] = -(k + damping_per_stiffness * k * dzd_dz) / mass


@kernel()
def friction_param_partials(v, y, s, p, o, g, row_f):
    """∂ż_i/∂θ into rows s + i and ∂F/∂θ into row_f for every θ of the block."""
    n = _blocks()
    size = GMS_COMMON + 2 * n
    for k in range(size):
        for i in range(2 * n):
            g[s + i, o + k] = 0.0
        g[row_f, o + k] = 0.0
    level, dg_dfc, dg_dfs, dg_dvs, dg_ddelta = stribeck_curve_params(
        v, p[o + GMS_FC], p[o + GMS_FS], p[o + GMS_VS], p[o + GMS_DELTA])
    if not level > RELAXED_LEVEL * p[o + GMS_FS]:
        g[row_f, o + GMS_SIGMA2] = v
        return
    shares = share_sum(p, o, n)
    c = p[o + GMS_C]
    for i in range(n):
        mode = y[s + n + i]
        if mode == 0.0:
            continue
        k = p[o + GMS_COMMON + i]
        nu = p[o + GMS_COMMON + n + i]
        _, dzd_dg, _ = _block_rate(v, y, s, p, o, i, n, level, True)
        direction = sign(mode)
        g[s + i, o + GMS_C] = direction * nu / (shares * k) - y[s + i] / level
        g[s + i, o + GMS_COMMON + i] = -c * direction * nu / (shares * k * k)
        for j in range(n):
            own = 1.0 / shares if j == i else 0.0
            g[s + i, o + GMS_COMMON + n + j] = c * direction / k * (own - nu / (shares
                                                                              * shares))
        g[s + i, o + GMS_FC] = dzd_dg * dg_dfc
        g[s + i, o + GMS_FS] = dzd_dg * dg_dfs
        g[s + i, o + GMS_VS] = dzd_dg * dg_dvs
        g[s + i, o + GMS_DELTA] = dzd_dg * dg_ddelta
    stiffness = _total_stiffness(p, o, n)
    sigma1 = p[o + GMS_SIGMA1]
    for kk in range(size):
        acc = 0.0
        for i in range(n):
            acc += p[o + GMS_COMMON + i] * g[s + i, o + kk]
        g[row_f, o + kk] = sigma1 * acc / stiffness
    damping = 0.0
    for i in range(n):
        damping += p[o + GMS_COMMON + i] * _block_rate(v, y, s, p, o, i, n, level, True)[0]
    g[row_f, o + GMS_SIGMA1] = damping / stiffness
    g[row_f, o + GMS_SIGMA2] = v
    for j in range(n):
        zdot = _block_rate(v, y, s, p, o, j, n, level, True)[0]
        g[row_f, o + GMS_COMMON + j] += y[s + j] + sigma1 * (zdot - damping / stiffness) \
            / stiffness


@kernel()
def friction_project(p, o, y, s):
    """A slipping block's |kᵢ·zᵢ| <= νᵢ·max(Fs, Fc)/Σν (its force approaches its share of
    g(v) <= max(Fs, Fc)). A stuck block is left alone: a step that carries it past its
    slip force is cut at the crossing by the event location, which must see it."""
    n = _blocks()
    shares = share_sum(p, o, n)
    level = max(p[o + GMS_FS], p[o + GMS_FC])
    for i in range(n):
        if y[s + n + i] == 0.0:
            continue
        bound = p[o + GMS_COMMON + n + i] * level / (shares * p[o + GMS_COMMON + i])
        y[s + i] = min(max(y[s + i], -bound), bound)


@kernel()
def friction_scales(p, o, out, s):
    """Each block's break-away deflection (its states' scale), 1 for the modes; the
    largest deflection, the total stiffness and no regularisation speed."""
    n = _blocks()
    shares = share_sum(p, o, n)
    level = max(p[o + GMS_FS], p[o + GMS_FC])
    largest = 0.0
    for i in range(n):
        k = p[o + GMS_COMMON + i]
        out[s + i] = presliding_scale(p[o + GMS_COMMON + n + i] * level / shares, k)
        out[s + n + i] = 1.0
        largest = max(largest, out[s + i])
    return largest, _total_stiffness(p, o, n), 0.0


# ------------------------------------------------------------------ the integrator's events
@kernel()
def _guard_of(v, y, prm, i, n, level):
    o = FRICTION_LO
    k = prm[o + GMS_COMMON + i]
    limit = prm[o + GMS_COMMON + n + i] * level / share_sum(prm, o, n)
    return guard(v, y[S_FRICTION + i], y[S_FRICTION + n + i], k, limit), k, limit


@kernel()
def event_guards(t, ts, y, prm, sig, ptr, out):
    """One guard per block into ``out``; returns how many."""
    n = _blocks()
    v = model_velocity(t, ts, y, prm, sig, ptr)
    level = _level(v, prm, FRICTION_LO)[0]
    for i in range(n):
        out[i] = _guard_of(v, y, prm, i, n, level)[0]
    return n


@kernel()
def event_switch(t, ts, y, prm, sig, ptr, forced):
    """Switch each block whose guard is <= 0 or that ``forced`` names (located at this
    instant): a stuck block starts to slip in the direction of motion, on its slip force;
    a slipping block sticks. Returns whether any block switched."""
    n = _blocks()
    v = model_velocity(t, ts, y, prm, sig, ptr)
    level = _level(v, prm, FRICTION_LO)[0]
    changed = False
    for i in range(n):
        margin, k, limit = _guard_of(v, y, prm, i, n, level)
        if margin > 0.0 and not forced[i]:
            continue
        if y[S_FRICTION + n + i] != 0.0:
            y[S_FRICTION + n + i] = 0.0
            changed = True
            continue
        # the direction the block is loaded in (that of the motion that loaded it; near a
        # reversal the velocity at the located instant may already point back)
        direction = sign(y[S_FRICTION + i]) if y[S_FRICTION + i] != 0.0 else sign(v)
        if direction != 0.0:
            y[S_FRICTION + n + i] = direction
            y[S_FRICTION + i] = direction * limit / k
            changed = True
    return changed
