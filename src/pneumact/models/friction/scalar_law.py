"""Kernel template: the slice-level friction functions of a law with one state.

The law itself is six scalar functions of its module, bound by the generator:
``friction_law(v, z, p, o) -> (ż, F, ∂ż/∂v, ∂ż/∂z, ∂F/∂v, ∂F/∂z)`` (inlined, so the hot
loop passes no arrays to it), ``friction_law_params(v, z, p, o, g, rz, rf)``,
``friction_law_scales(p, o) -> (typical z, stiffness, v_reg)`` and
``friction_law_bound(p, o) -> largest |z|``. These functions give them the interface of
``models.friction.base`` on the state ``y[s]``.
"""

from pneumact.core import kernel

# --- bound by the generator --------------------------------------------------------------
friction_law = friction_law_params = friction_law_scales = friction_law_bound = None
# ------------------------------------------------------------------------------------------


@kernel(inline="always")
def friction_rates(v, y, s, p, o):
    zdot, force, _, _, _, _ = friction_law(v, y[s], p, o)
    return force, zdot


@kernel(inline="always")
def friction_store(rates, dydt, s):
    dydt[s] = rates


@kernel(inline="always")
def friction_force(v, y, s, p, o):
    return friction_law(v, y[s], p, o)[1]


@kernel(inline="always")
def friction_partials(v, y, s, p, o):
    _, force, dzd_dv, dzd_dz, df_dv, df_dz = friction_law(v, y[s], p, o)
    return force, df_dv, (dzd_dv, dzd_dz, df_dz)


@kernel(inline="always")
def friction_store_partials(partials, jac, s, col_v, row_f, mass):
    dzd_dv, dzd_dz, df_dz = partials
    jac[s, s] = dzd_dz
    if col_v >= 0:
        jac[s, col_v] = dzd_dv
    if row_f >= 0:
        jac[row_f, s] = -df_dz / mass


@kernel(inline="always")
def friction_param_partials(v, y, s, p, o, g, row_f):
    friction_law_params(v, y[s], p, o, g, s, row_f)


@kernel(inline="always")
def friction_project(p, o, y, s):
    bound = friction_law_bound(p, o)
    y[s] = min(max(y[s], -bound), bound)


@kernel(inline="always")
def friction_scales(p, o, out, s):
    z_scale, stiffness, v_reg = friction_law_scales(p, o)
    out[s] = z_scale
    return z_scale, stiffness, v_reg
