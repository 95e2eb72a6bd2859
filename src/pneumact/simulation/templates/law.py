"""Template: one friction law on its own, evaluated over arrays (tests and plots).

Bound to a friction law by the generator; the parameter vector is the law's block.
"""

import numpy as np

from pneumact.simulation.codegen import kernel

# --- bound by the generator --------------------------------------------------------------
friction_eval = friction_params = None
FRICTION_LO = FRICTION_HI = 0
# ------------------------------------------------------------------------------------------

OUTPUT_NAMES = ()
OUTPUT_UNITS = ()


@kernel()
def derive(prm):
    """A friction law derives nothing."""


@kernel()
def law_values(v, z, prm, out):
    """out[i] = (dz/dt, F, ∂(dz/dt)/∂v, ∂(dz/dt)/∂z, ∂F/∂v, ∂F/∂z) at (v[i], z[i])."""
    for i in range(v.shape[0]):
        r = friction_eval(v[i], z[i], prm, FRICTION_LO)
        for j in range(6):
            out[i, j] = r[j]


@kernel()
def law_parameter_derivatives(v, z, prm, dzdot, dforce):
    """dzdot[i, k], dforce[i, k]: ∂(dz/dt)/∂p_k and ∂F/∂p_k of the law's block at i."""
    g = np.zeros((2, prm.shape[0]))
    for i in range(v.shape[0]):
        friction_params(v[i], z[i], prm, FRICTION_LO, g, 0, 1)
        for k in range(FRICTION_HI - FRICTION_LO):
            dzdot[i, k] = g[0, FRICTION_LO + k]
            dforce[i, k] = g[1, FRICTION_LO + k]
