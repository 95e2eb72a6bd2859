"""Kernel template: two friction laws on one body, placed as the instances
``friction_piston`` and ``friction_rod`` (``Cylinder(friction={"piston": ..., "rod":
...})``), behind the slice-level interface of one law (``models.friction.base``).

Each law's own slice functions are a child kernel (``core.codegen.Child``: its template,
``scalar_law`` or ``stateless_law``, bound to its functions), exposed here under the
prefixes ``piston_`` and ``rod_``; each reads its own states at ``S_FRICTION_PISTON``,
``S_FRICTION_ROD`` and its own block at ``FRICTION_PISTON_LO``, ``FRICTION_ROD_LO``
(generated), whatever slice the model template passes (the span of both). The force is
the sum of the two laws'; the rates, partials and bounds are each law's on its own
slice and block. A law that holds model-level functions (GMS's events) is placed alone.
"""

from pneumact.core import kernel

# --- bound by the generator --------------------------------------------------------------
piston_friction_rates = piston_friction_store = piston_friction_force = None
piston_friction_partials = piston_friction_store_partials = None
piston_friction_param_partials = piston_friction_project = piston_friction_scales = None
rod_friction_rates = rod_friction_store = rod_friction_force = None
rod_friction_partials = rod_friction_store_partials = None
rod_friction_param_partials = rod_friction_project = rod_friction_scales = None
S_FRICTION_PISTON = S_FRICTION_ROD = 0
FRICTION_PISTON_LO = FRICTION_ROD_LO = 0
# ------------------------------------------------------------------------------------------


@kernel(inline="always")
def friction_rates(v, y, s, p, o):
    """The summed force; each law's rates, stored by ``friction_store``."""
    force_a, rates_a = piston_friction_rates(v, y, S_FRICTION_PISTON, p, FRICTION_PISTON_LO)
    force_b, rates_b = rod_friction_rates(v, y, S_FRICTION_ROD, p, FRICTION_ROD_LO)
    return force_a + force_b, (rates_a, rates_b)


@kernel(inline="always")
def friction_store(rates, dydt, s):
    piston_friction_store(rates[0], dydt, S_FRICTION_PISTON)
    rod_friction_store(rates[1], dydt, S_FRICTION_ROD)


@kernel(inline="always")
def friction_force(v, y, s, p, o):
    return (piston_friction_force(v, y, S_FRICTION_PISTON, p, FRICTION_PISTON_LO)
            + rod_friction_force(v, y, S_FRICTION_ROD, p, FRICTION_ROD_LO))


@kernel(inline="always")
def friction_partials(v, y, s, p, o):
    """The summed force and ∂F/∂v; each law's state partials."""
    force_a, dv_a, partials_a = piston_friction_partials(v, y, S_FRICTION_PISTON, p,
                                                         FRICTION_PISTON_LO)
    force_b, dv_b, partials_b = rod_friction_partials(v, y, S_FRICTION_ROD, p,
                                                      FRICTION_ROD_LO)
    return force_a + force_b, dv_a + dv_b, (partials_a, partials_b)


@kernel(inline="always")
def friction_store_partials(partials, jac, s, col_v, row_f, mass):
    piston_friction_store_partials(partials[0], jac, S_FRICTION_PISTON, col_v, row_f, mass)
    rod_friction_store_partials(partials[1], jac, S_FRICTION_ROD, col_v, row_f, mass)


@kernel(inline="always")
def friction_param_partials(v, y, s, p, o, g, row_f):
    """Each law's columns (its own block): the force's row is the sum's."""
    piston_friction_param_partials(v, y, S_FRICTION_PISTON, p, FRICTION_PISTON_LO, g, row_f)
    rod_friction_param_partials(v, y, S_FRICTION_ROD, p, FRICTION_ROD_LO, g, row_f)


@kernel(inline="always")
def friction_project(p, o, y, s):
    piston_friction_project(p, FRICTION_PISTON_LO, y, S_FRICTION_PISTON)
    rod_friction_project(p, FRICTION_ROD_LO, y, S_FRICTION_ROD)


@kernel(inline="always")
def friction_scales(p, o, out, s):
    """Each law's state scales; (the larger range, the summed stiffness, the smaller
    nonzero regularisation speed)."""
    range_a, stiffness_a, reg_a = piston_friction_scales(p, FRICTION_PISTON_LO, out,
                                                         S_FRICTION_PISTON)
    range_b, stiffness_b, reg_b = rod_friction_scales(p, FRICTION_ROD_LO, out, S_FRICTION_ROD)
    reg = min(reg_a, reg_b) if reg_a > 0.0 and reg_b > 0.0 else max(reg_a, reg_b)
    return max(range_a, range_b), stiffness_a + stiffness_b, reg
