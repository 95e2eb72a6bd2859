"""Template: the batch engine's inner loop, many parameter sets in one compiled call.

For each row: set the row's values into a copy of the base vector, re-derive, find the
initial state, set the tolerances from the row's state scales, integrate, then compute
every feature and copy the requested signals, all without the Python interpreter, so
threads running chunks in parallel never wait on the GIL.
"""

import numpy as np

from pneumact.core import kernel
from pneumact.core.features import N_FEATURES, all_features
from pneumact.core.integrators import INFO_LENGTH, INFO_STATUS

# --- bound by the generator and the other templates --------------------------------------
derive = initial_state = state_scales = integrate_rodas4 = integrate_dopri5 = None
NSTATE = 3
NOUT = None  # generated from the model's outputs
#: the model writes its own input (a closed loop's controller output) into ``sig``
PRIVATE_INPUTS = False
# ------------------------------------------------------------------------------------------

#: where a feature reads a signal: from the states or from the derived outputs
FROM_STATE = 0
FROM_OUTPUT = 1
#: the signals the features are computed from: the rows of ``sources``, in this order
FEATURE_SIGNALS = ("position", "velocity", "pressure")
ROW_POSITION = FEATURE_SIGNALS.index("position")
ROW_VELOCITY = FEATURE_SIGNALS.index("velocity")
ROW_PRESSURE = FEATURE_SIGNALS.index("pressure")


@kernel(nogil=True)
def run_rows(prm0, slot_ptr, slot_idx, values, valid, y0_given, sig, ptr, tb, t_out,
             explicit, rtol, atol_given, h_init, h_max, max_steps, sources, ref_t, ref_x,
             want_features, features, signal_sources, signals, info_rows):
    """Simulate every ``valid`` row of ``values`` (n × columns, SI).

    Column c writes the vector slots slot_idx[slot_ptr[c]:slot_ptr[c+1]]. ``y0_given``
    (NSTATE values, or empty) replaces the equilibrium start; ``explicit``: None for
    Rodas4 (the other integrator is then not compiled), True for Dormand-Prince;
    ``atol_given[i] > 0``
    replaces rtol × scale of state i. ``sources`` (one row per FEATURE_SIGNALS: kind,
    column) says where each is (kind −1: none, for the pressure); ``features`` (n ×
    N_FEATURES, when ``want_features``) and ``signals`` (n × k × n_t, from
    ``signal_sources``) are written for the rows that succeed; ``info_rows`` (n ×
    INFO_LENGTH) gets each row's solver info.
    """
    n_t = t_out.shape[0]
    y_out = np.empty((n_t, NSTATE))
    out = np.empty((n_t, NOUT))
    info = np.zeros(INFO_LENGTH)
    y0 = np.empty(NSTATE)
    scales = np.empty(NSTATE)
    atol = np.empty(NSTATE)
    feats = np.empty(N_FEATURES)
    ts0 = 0.5 * (tb[0] + tb[1])
    has_reference = ref_t.shape[0] >= 2
    for r in range(values.shape[0]):
        if not valid[r]:
            continue
        # a closed loop writes its controller output into its own copy of the inputs
        sig_row = sig.copy() if PRIVATE_INPUTS else sig
        prm = prm0.copy()
        for c in range(values.shape[1]):
            for k in range(slot_ptr[c], slot_ptr[c + 1]):
                prm[slot_idx[k]] = values[r, c]
        derive(prm)
        if y0_given.shape[0] == NSTATE:
            for i in range(NSTATE):
                y0[i] = y0_given[i]
        else:
            initial_state(tb[0], ts0, prm, sig_row, ptr, y0)
        state_scales(prm, scales)
        for i in range(NSTATE):
            atol[i] = atol_given[i] if atol_given[i] > 0.0 else rtol * scales[i]
        if explicit is None:
            integrate_rodas4(y0, prm, sig_row, ptr, tb, t_out, rtol, atol, h_init, h_max,
                             max_steps, y_out, out, info)
        else:
            integrate_dopri5(y0, prm, sig_row, ptr, tb, t_out, rtol, atol, h_init, h_max,
                             max_steps, y_out, out, info)
        for i in range(INFO_LENGTH):
            info_rows[r, i] = info[i]
        if info[INFO_STATUS] != 0:
            continue
        if want_features:
            _features(t_out, y_out, out, sources, ref_t, ref_x, has_reference, feats)
            for k in range(N_FEATURES):
                features[r, k] = feats[k]
        for s in range(signal_sources.shape[0]):
            column = _column(y_out, out, signal_sources[s, 0], signal_sources[s, 1])
            for j in range(n_t):
                signals[r, s, j] = column[j]


@kernel()
def _features(t_out, y_out, out, sources, ref_t, ref_x, has_reference, feats):
    """Every feature of one run, from the columns ``sources`` points at."""
    x = _column(y_out, out, sources[ROW_POSITION, 0], sources[ROW_POSITION, 1])
    v = _column(y_out, out, sources[ROW_VELOCITY, 0], sources[ROW_VELOCITY, 1])
    has_pressure = sources[ROW_PRESSURE, 0] >= 0
    p = (_column(y_out, out, sources[ROW_PRESSURE, 0], sources[ROW_PRESSURE, 1])
         if has_pressure else x)
    all_features(t_out, x, v, p, has_pressure, ref_t, ref_x, has_reference, feats)


@kernel()
def _column(y_out, out, kind, index):
    """A contiguous copy of one signal: a state column or a derived-output column."""
    if kind == FROM_STATE:
        return np.ascontiguousarray(y_out[:, index])
    return np.ascontiguousarray(out[:, index])
