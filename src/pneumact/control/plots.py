"""The closed-loop figure: set-point and position, command, friction and velocity.

Display units as in ``pneumact.plotting`` (mm, mm/s, kPa, N); returns the Figure and
never calls ``plt.show()`` nor chooses a backend.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..plotting import display_values, has_signal, new_axes, signal_values, tight_layout
from .metrics import LoopMetrics, _rise_times

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["plot_loop"]

_MM = 1e3


def plot_loop(result: Any, metrics: LoopMetrics | None = None) -> Figure:
    """Four panels over a shared time axis [s]: (1) set-point and position [mm], with
    the settling band (target ± band·|step|), the rise (10 % to 90 %, shaded) and the
    settling time (dotted line) when ``metrics`` (from ``loop_metrics``) are given;
    (2) the command, in its display unit; (3) friction and, where it is not zero
    throughout, the friction compensation [N]; (4) velocity [mm/s]. ``result``: a Result
    or a DataFrame with the same signals (``time``, ``position``, ``position_setpoint`` required).
    The key metrics go into the title. Returns the Figure."""
    time = signal_values(result, "time")
    position = signal_values(result, "position")
    setpoint = signal_values(result, "position_setpoint")
    fig, (ax_x, ax_u, ax_f, ax_v) = new_axes(4, height=9.0)

    ax_x.plot(time, setpoint * _MM, "k--", linewidth=1.0, label="set-point")
    ax_x.plot(time, position * _MM, "C0-", label="position")
    if metrics is not None:
        _mark_step(ax_x, time, position, metrics)
    ax_x.set_ylabel("position [mm]")
    ax_x.legend(loc="best", fontsize=8)

    if has_signal(result, "command"):
        values, label = display_values(result, "command")
        ax_u.plot(time, values, "C1-")
        ax_u.set_ylabel(label)
    else:
        _absent(ax_u, "command")

    if has_signal(result, "friction"):
        ax_f.plot(time, signal_values(result, "friction"), "C3-", label="friction")
        if has_signal(result, "friction_compensation"):
            compensation = signal_values(result, "friction_compensation")
            if np.any(compensation != 0.0):
                ax_f.plot(time, compensation, "C2-", linewidth=1.0,
                          label="friction compensation")
                ax_f.legend(loc="best", fontsize=8)
        ax_f.set_ylabel("friction [N]")
    else:
        _absent(ax_f, "friction")

    if has_signal(result, "velocity"):
        velocity = signal_values(result, "velocity")
        ax_v.plot(time, velocity * _MM, "C4-")
        if metrics is not None and metrics.stick_speed > 0:
            for sign in (-1.0, 1.0):
                ax_v.axhline(sign * metrics.stick_speed * _MM, color="0.5", linewidth=0.6,
                             linestyle=":")
        ax_v.set_ylabel("velocity [mm/s]")
    else:
        _absent(ax_v, "velocity")
    ax_v.set_xlabel("time [s]")

    for ax in (ax_x, ax_u, ax_f, ax_v):
        ax.grid(True, alpha=0.3)
    if metrics is not None:
        fig.suptitle(metrics.summary(), fontsize=9)
    tight_layout(fig)
    return fig


def _mark_step(ax, time: np.ndarray, position: np.ndarray, metrics: LoopMetrics) -> None:
    """Settling band, rise interval and settling time on the position panel."""
    if metrics.step == 0:
        return
    half = metrics.band_width
    ax.axhspan((metrics.target - half) * _MM, (metrics.target + half) * _MM, color="C2",
               alpha=0.15, label=f"±{100 * metrics.band:g} % band")
    t10, t90 = _rise_times(time, position, metrics.t_step, metrics.start, metrics.target)
    if math.isfinite(t10) and math.isfinite(t90):
        ax.axvspan(t10, t90, color="C1", alpha=0.15, label=f"rise {t90 - t10:.3g} s")
    if math.isfinite(metrics.settling_time):
        t_settled = metrics.t_step + metrics.settling_time
        ax.axvline(t_settled, color="C2", linestyle=":",
                   label=f"settled {metrics.settling_time:.3g} s after the step")


def _absent(ax, name: str) -> None:
    ax.text(0.5, 0.5, f"no {name} signal", transform=ax.transAxes, ha="center",
            va="center", color="0.5")
    ax.set_ylabel(name)
