"""Mechanics of the diaphragm actuator (paper eq. 1): spring, pressure force, end stops.

    m·dv/dt = (p_atm − p)·A_d − (F0 + k·x) − F_f − F_ext(t, x) + F_stop(x, v)

The end stops are Hunt–Crossley contacts: F = k_stop·δ + c_stop·δ·dδ/dt on the
penetration δ, never negative. The force is continuous at first contact (zero at δ = 0),
so the right-hand side has no jump there and forward sensitivities stay exact through
impacts; it never pulls and its damping only dissipates (c_stop·δ·δ̇² ≥ 0).

The compiled functions read the block ``MECHANICS_BLOCK``, which starts at offset ``o``
of the parameter vector ``p``, through the local indices below; as in ``friction``, the
maths is in scalar-only functions and the array-reading wrappers are inlined.
"""

from __future__ import annotations

from ..core.channels import CH_LOAD_T, CH_LOAD_X
from ..core.component import Block
from ..core.jit import njit
from ..core.signals import channel_eval
from ..parameters.catalogue import ParameterSpec, declare

P = ParameterSpec
declare(
    P("m", "kg", "moving mass (diaphragm, rod, linkage)", None, 1e-9, False, 1e5,
      group="mechanics", plausible=(1e-3, 1e3)),
    P("F0", "N", "spring preload at the rest stop", None, 0.0, False, 1e7, group="mechanics",
      plausible=(0.0, 1e5)),
    # plausible k: VGT and wastegate springs ~1e4 N/m, large valve actuators up to ~1e6
    P("k", "N/m", "spring (+ membrane) stiffness", None, 0.0, False, 1e10,
      group="mechanics", plausible=(0.0, 1e6)),
    P("x_max", "m", "stroke: position of the far end stop", None, 0.0, True, 10.0,
      group="mechanics", plausible=(1e-4, 2.0)),
    P("k_stop", "N/m", "end-stop contact stiffness (penalty)", 1e8, 0.0, True, 1e14,
      group="mechanics", plausible=(1e5, 1e12)),
    # c_stop: critically damps vgt-paper's diaphragm resting on its stop (penetration
    # δ0 = F0/k_stop = 0.33 µm; c_stop·δ0 = 2·sqrt(k_stop·m)): its fastest pole moves
    # from −5.2e5 (the former 1e12) to −1.7e4 1/s, and loop widths by < 3e-6 (issue 39)
    P("c_stop", "N*s/m^2", "end-stop Hunt-Crossley damping: force c_stop·δ·dδ/dt on the "
      "penetration δ", 5e10, 0.0, False, 1e18, group="mechanics"),
    P("A_d", "m^2", "effective diaphragm area", None, 0.0, True, 10.0, group="pneumatics",
      plausible=(1e-6, 1.0)),
    P("p_atm", "Pa", "atmospheric pressure (absolute)", None, 1e3, False, 1e7,
      group="pneumatics", plausible=(50e3, 110e3)),
)

MECHANICS_BLOCK = Block.of("m", "F0", "k", "x_max", "k_stop", "c_stop", "A_d", "p_atm")
MC_M = MECHANICS_BLOCK.index("m")
MC_F0 = MECHANICS_BLOCK.index("F0")
MC_K = MECHANICS_BLOCK.index("k")
MC_XMAX = MECHANICS_BLOCK.index("x_max")
MC_KSTOP = MECHANICS_BLOCK.index("k_stop")
MC_CSTOP = MECHANICS_BLOCK.index("c_stop")
MC_AD = MECHANICS_BLOCK.index("A_d")
MC_PATM = MECHANICS_BLOCK.index("p_atm")



@njit(cache=True)
def _contact(pen, pen_rate, ks, cs):  # pragma: no cover - compiled
    """Hunt–Crossley force on penetration ``pen`` > 0 and its partials (pen, pen_rate)."""
    f = pen * (ks + cs * pen_rate)
    if f <= 0.0:
        return 0.0, 0.0, 0.0
    return f, ks + cs * pen_rate, cs * pen


@njit(cache=True)
def stop_force(x, v, ks, cs, x_max):  # pragma: no cover - compiled
    """End-stop force (positive pushes towards larger x) and its partials (∂x, ∂v)."""
    if x < 0.0:
        f, df_dpen, df_drate = _contact(-x, -v, ks, cs)
        return f, -df_dpen, -df_drate
    pen = x - x_max
    if pen > 0.0:
        f, df_dpen, df_drate = _contact(pen, v, ks, cs)
        return -f, -df_dpen, -df_drate
    return 0.0, 0.0, 0.0


@njit(cache=True)
def stop_guards(x, p, o):  # pragma: no cover - compiled
    """Where the end-stop force switches on: x = 0 (the rest stop) and x = x_max, each
    guard > 0 off its stop. The right-hand side has a kink there: an FMU importer's solver
    locates these as state events (``export``)."""
    return x, p[o + MC_XMAX] - x


@njit(cache=True)
def stop_force_params(x, v, ks, cs, x_max):  # pragma: no cover - compiled
    """(∂F_stop/∂k_stop, ∂F_stop/∂c_stop, ∂F_stop/∂x_max)."""
    if x < 0.0:
        if -x * (ks - cs * v) > 0.0:
            return -x, x * v, 0.0
        return 0.0, 0.0, 0.0
    pen = x - x_max
    if pen > 0.0 and pen * (ks + cs * v) > 0.0:
        return -pen, -pen * v, ks + cs * v
    return 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def stop_force_of(x, v, p, o):  # pragma: no cover - compiled
    return stop_force(x, v, p[o + MC_KSTOP], p[o + MC_CSTOP], p[o + MC_XMAX])


@njit(cache=True, inline="always")
def load_against_time(t, ts, sig, ptr):  # pragma: no cover - compiled
    """External load F_ext(t) [N], opposing motion towards larger x."""
    return channel_eval(sig, ptr, CH_LOAD_T, t, ts)[0]


@njit(cache=True, inline="always")
def load_against_position(x, sig, ptr):  # pragma: no cover - compiled
    """External load F_ext(x) [N] and its slope."""
    return channel_eval(sig, ptr, CH_LOAD_X, x, x)


@njit(cache=True)
def net_force_law(x, v, pressure, f_fric, f_ext, f0, k, ad, p_atm, ks, cs,
                  x_max):  # pragma: no cover - compiled
    """Sum of forces on the moving mass and its partials (∂x, ∂v, ∂pressure; the
    friction and the external load enter with −1)."""
    f_stop, ds_dx, ds_dv = stop_force(x, v, ks, cs, x_max)
    net = (p_atm - pressure) * ad - (f0 + k * x) - f_fric - f_ext + f_stop
    return net, -k + ds_dx, ds_dv, -ad


@njit(cache=True, inline="always")
def net_force(x, v, pressure, f_fric, f_ext, p, o):  # pragma: no cover - compiled
    return net_force_law(x, v, pressure, f_fric, f_ext, p[o + MC_F0], p[o + MC_K],
                         p[o + MC_AD], p[o + MC_PATM], p[o + MC_KSTOP], p[o + MC_CSTOP],
                         p[o + MC_XMAX])


@njit(cache=True)
def acceleration_params(x, v, pressure, net, p, o, g, row):  # pragma: no cover - compiled
    """g[row, o + k] = ∂(dv/dt)/∂p_k for the mechanics block (dv/dt = net/m)."""
    m = p[o + MC_M]
    dks, dcs, dxmax = stop_force_params(x, v, p[o + MC_KSTOP], p[o + MC_CSTOP],
                                        p[o + MC_XMAX])
    g[row, o + MC_M] = -net / (m * m)
    g[row, o + MC_F0] = -1.0 / m
    g[row, o + MC_K] = -x / m
    g[row, o + MC_XMAX] = dxmax / m
    g[row, o + MC_KSTOP] = dks / m
    g[row, o + MC_CSTOP] = dcs / m
    g[row, o + MC_AD] = (p[o + MC_PATM] - pressure) / m
    g[row, o + MC_PATM] = p[o + MC_AD] / m


@njit(cache=True)
def rest_position(net0, k, ks, x_max):  # pragma: no cover - compiled
    """Where the spring (and an end stop) balance the net force ``net0`` [N] that acts at
    x = 0 towards larger x, at rest (the stop's damping plays no part)."""
    if k > 0.0:
        x_free = net0 / k
    else:
        x_free = 0.0 if net0 <= 0.0 else x_max
    if x_free <= 0.0:
        return net0 / (k + ks)
    if x_free >= x_max:
        return x_max + (net0 - k * x_max) / (k + ks)
    return x_free


@njit(cache=True)
def mechanics_scales(p, o):  # pragma: no cover - compiled
    """Typical magnitudes of position and velocity: the stroke, and 10 strokes per second."""
    return p[o + MC_XMAX], 10.0 * p[o + MC_XMAX]


def explicit_step_limit(m: float, k: float, f0: float, k_stop: float, c_stop: float
                        ) -> float:
    """The largest stable forward-Euler step [s] on the rest stop under the preload ``f0``.

    Resting at the penetration δ0 = F0/(k_stop + k), the contact linearises to
    m·s² + c_stop·δ0·s + (k_stop + k): Euler is stable for h < 2/|λ| on a real pole and
    h < 2·Re(−λ)/|λ|² on a complex pair. The FMU's end-stop check (``export``) states the
    same figure when an explicit importer goes unstable there. No preload: the diaphragm
    rests free of the stop, and the rest sets no limit (inf).
    """
    if f0 <= 0.0:
        return float("inf")
    stiffness = k_stop + k
    damping = c_stop * f0 / stiffness
    disc = damping * damping - 4.0 * stiffness * m
    if disc >= 0.0:
        return 4.0 * m / (damping + disc**0.5)
    return damping / stiffness


def explicit_step(m: float, k: float, f0: float, k_stop: float, c_stop: float) -> float:
    """A forward-Euler step [s] that stays stable on the end stops: half the smaller of
    the resting limit (``explicit_step_limit``) and sqrt(m/k_stop), the contact's time
    scale as the diaphragm lifts off (Hunt–Crossley damping vanishes with the
    penetration), rounded down to 1, 2 or 5 × 10ⁿ. vgt-paper: 20 µs (Euler at 50 µs
    still runs, at 100 µs it does not)."""
    import math

    bound = 0.5 * min(explicit_step_limit(m, k, f0, k_stop, c_stop), (m / k_stop) ** 0.5)
    decade = 10.0 ** math.floor(math.log10(bound))
    return max(f * decade for f in (1.0, 2.0, 5.0) if f * decade <= bound)
