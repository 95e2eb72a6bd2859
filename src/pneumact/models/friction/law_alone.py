"""Template: one friction law on its own, evaluated over arrays (tests and plots).

Bound to a friction law by the generator; the state vector is the law's states
(NSTATE of them, from 0), the parameter vector the law's block. The velocity takes the
column NSTATE of a local Jacobian, the force its row NSTATE.
"""

import numpy as np

from pneumact.core import kernel

# --- bound by the generator --------------------------------------------------------------
friction_rates = friction_partials = friction_param_partials = None
friction_store = friction_store_partials = None
NSTATE = 1
FRICTION_LO = FRICTION_HI = 0
S_FRICTION = 0
# ------------------------------------------------------------------------------------------

OUTPUT_NAMES = ()
OUTPUT_UNITS = ()


@kernel()
def derive(prm):
    """A friction law derives nothing."""


@kernel()
def law_values(v, y, prm, force, dforce_dv, rates, jac):
    """At (v[i], y[i]): force, ∂F/∂v, the rates; jac[i] is the law's Jacobian with the
    velocity as column NSTATE and the force (×−1: the row of a unit mass) as row NSTATE."""
    dydt = np.zeros(NSTATE)
    for i in range(v.shape[0]):
        force[i], z_rates = friction_rates(v[i], y[i], S_FRICTION, prm, FRICTION_LO)
        friction_store(z_rates, dydt, S_FRICTION)
        for j in range(NSTATE):
            rates[i, j] = dydt[j]
        _, dforce_dv[i], z_partials = friction_partials(v[i], y[i], S_FRICTION, prm,
                                                        FRICTION_LO)
        friction_store_partials(z_partials, jac[i], S_FRICTION, NSTATE, NSTATE, 1.0)


@kernel()
def law_parameter_derivatives(v, y, prm, g):
    """g[i, j, k]: ∂ż_j/∂p_k (j < NSTATE) and ∂F/∂p_k (j = NSTATE) of the law's block."""
    for i in range(v.shape[0]):
        friction_param_partials(v[i], y[i], S_FRICTION, prm, FRICTION_LO, g[i], NSTATE)
