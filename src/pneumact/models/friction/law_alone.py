"""Template: one friction law on its own, evaluated over arrays (tests and plots).

Bound to a friction law by the generator. The law does not sit at the start of the
vectors: a one-state, one-parameter component comes first (``models.friction.evaluation``),
so a law that reads or writes its slice at a fixed index instead of at its offsets
(``s``, ``o``) gives wrong values here, as it would in a model. That first state's slot is
the velocity's column of a local Jacobian and the force's row; the law's states are
NSTATE − S_FRICTION of them, from S_FRICTION.
"""

import numpy as np

from pneumact.core import kernel

# --- bound by the generator --------------------------------------------------------------
friction_rates = friction_partials = friction_param_partials = None
friction_store = friction_store_partials = None
NSTATE = 2
FRICTION_LO = FRICTION_HI = 1
S_FRICTION = 1
# ------------------------------------------------------------------------------------------

OUTPUT_NAMES = ()
OUTPUT_UNITS = ()
#: the slot of the velocity (a Jacobian's column) and of the force (its row)
MOTION = 0


@kernel()
def derive(prm):
    """A friction law derives nothing."""


@kernel()
def law_values(v, y, prm, force, dforce_dv, rates, jac):
    """At (v[i], y[i]) (y[i] the whole vector, the law's states from S_FRICTION): force,
    ∂F/∂v, the rates of the whole vector; jac[i] the Jacobian with the velocity as column
    MOTION and the force (×−1: the row of a unit mass) as row MOTION."""
    dydt = np.zeros(NSTATE)
    for i in range(v.shape[0]):
        force[i], z_rates = friction_rates(v[i], y[i], S_FRICTION, prm, FRICTION_LO)
        friction_store(z_rates, dydt, S_FRICTION)
        for j in range(NSTATE):
            rates[i, j] = dydt[j]
        _, dforce_dv[i], z_partials = friction_partials(v[i], y[i], S_FRICTION, prm,
                                                        FRICTION_LO)
        friction_store_partials(z_partials, jac[i], S_FRICTION, MOTION, MOTION, 1.0)


@kernel()
def law_parameter_derivatives(v, y, prm, g):
    """g[i, j, k]: ∂ż_j/∂p_k (rows from S_FRICTION) and ∂F/∂p_k (row MOTION)."""
    for i in range(v.shape[0]):
        friction_param_partials(v[i], y[i], S_FRICTION, prm, FRICTION_LO, g[i], MOTION)
