"""Kernel template: the slice-level friction functions of a law with no state.

A static map F(v) is two scalar functions of its module, bound by the generator:
``friction_law(v, z, p, o)`` (the six-value form of ``scalar_law``, its state terms zero;
``z`` is ignored) and ``friction_law_params(v, z, p, o, g, rz, rf)``, called with
``rz = rf`` (it clears both rows, then writes ∂F/∂p into ``rf``), and
``friction_law_scales(p, o)``. The map has no slice: nothing is written to ``dydt``,
the Jacobian's state columns or the state scales.
"""

from pneumact.core import kernel

# --- bound by the generator --------------------------------------------------------------
friction_law = friction_law_params = friction_law_scales = None
# ------------------------------------------------------------------------------------------


@kernel(inline="always")
def friction_rates(v, y, s, p, o):
    return friction_law(v, 0.0, p, o)[1], 0.0


@kernel(inline="always")
def friction_store(rates, dydt, s):
    """No state, no rate to store."""


@kernel(inline="always")
def friction_force(v, y, s, p, o):
    return friction_law(v, 0.0, p, o)[1]


@kernel(inline="always")
def friction_partials(v, y, s, p, o):
    r = friction_law(v, 0.0, p, o)
    return r[1], r[4], 0.0


@kernel(inline="always")
def friction_store_partials(partials, jac, s, col_v, row_f, mass):
    """No state, no Jacobian entry."""


@kernel(inline="always")
def friction_param_partials(v, y, s, p, o, g, row_f):
    friction_law_params(v, 0.0, p, o, g, row_f, row_f)


@kernel(inline="always")
def friction_project(p, o, y, s):
    """A static map has no state to bound."""


@kernel(inline="always")
def friction_scales(p, o, out, s):
    return friction_law_scales(p, o)
