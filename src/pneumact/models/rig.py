"""Friction test rig: a mass with friction, driven for the classic friction experiments.

The drives are compiled functions ``drive(t, ts, y, prm, sig, ptr)`` returning
``(kinematic, v, a, F, ∂F/∂x, ∂F/∂v, drive_value, 0)``: a kinematic drive prescribes the
velocity (and acceleration) of the mass, a force drive applies a force to it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numba import njit

from ..experiments.signals import channel_eval
from .friction import FrictionModel, LuGre
from .layout import CH_DRIVE, I_KDRIVE


@njit(cache=True, inline="always")
def force_drive(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    """A force F(t) [N] applied to the mass."""
    f = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    return False, 0.0, 0.0, f, 0.0, 0.0, f, 0.0


@njit(cache=True, inline="always")
def spring_drive(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    """A spring k_drive whose free end follows x_d(t) [m] pulls the mass (stick-slip)."""
    xd = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    kd = prm[I_KDRIVE]
    return False, 0.0, 0.0, kd * (xd - y[0]), -kd, 0.0, xd, 0.0


@njit(cache=True, inline="always")
def velocity_drive(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    """The velocity v(t) [m/s] of the mass is prescribed."""
    v, a = channel_eval(sig, ptr, CH_DRIVE, t, ts)
    return True, v, a, 0.0, 0.0, 0.0, v, 0.0


@njit(cache=True, inline="always")
def position_drive(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    """The position x(t) [m] of the mass is prescribed (velocity = its slope)."""
    x, v = channel_eval(sig, ptr, CH_DRIVE, t, ts)
    dt = 1e-7 * max(1.0, abs(t))
    v2 = channel_eval(sig, ptr, CH_DRIVE, t + dt, ts)[1]
    return True, v, (v2 - v) / dt, 0.0, 0.0, 0.0, x, 0.0


DRIVES = {
    "force": ("N", "force applied to the mass"),
    "spring": ("m", "position of the pulling spring's free end"),
    "velocity": ("m/s", "prescribed velocity of the mass"),
    "position": ("m", "prescribed position of the mass"),
}


@dataclass(frozen=True)
class FrictionRig:
    """A mass ``m`` with a friction law, driven by ``drive`` (force, spring, velocity or
    position) — the set-up of Canudas de Wit et al. (1995) for the classic experiments."""

    params: object
    friction: FrictionModel = field(default_factory=LuGre)
    drive: str = "force"
    model: ClassVar[str] = "rig"
    initial_state_parameters: ClassVar[frozenset[str]] = frozenset()  # set by the drive

    def __post_init__(self):
        from ..errors import ExperimentError

        if self.drive not in DRIVES:
            raise ExperimentError(
                f"FrictionRig: drive = {self.drive!r}; allowed: {', '.join(DRIVES)}"
            )
        needed = ["m", *self.friction.required]
        if self.drive == "spring":
            needed.append("k_drive")
        self.params.require(needed, "FrictionRig")

    @property
    def drive_unit(self) -> str:
        return DRIVES[self.drive][0]

    def components(self) -> dict[str, str]:
        """What the kernel generator substitutes into the rig template."""
        return {
            "friction_eval": f"pneumact.models.friction:{self.friction.kernel}",
            "friction_dtheta": f"pneumact.models.friction:{self.friction.kernel}_dtheta",
            "drive_eval": f"pneumact.models.rig:{self.drive}_drive",
        }

    def kernel_key(self) -> str:
        return f"rig_{self.friction.kernel}_{self.drive}"

    def vector(self):
        return self.params.vector()

    def state_scales(self, prm) -> np.ndarray:
        """Typical magnitude of x, v, z: the presliding range Fs/σ0 and its velocity
        Fs/√(σ0·m) (static maps: the regularisation velocity), for default atol."""
        p = self.params
        if "sigma0" in self.friction.required:
            x = p["Fs"] / p["sigma0"] if "Fs" in self.friction.required else p["Fc"] / p["sigma0"]
            v = x * np.sqrt(p["sigma0"] / p["m"])
        else:
            v = p["v_reg"]
            x = v * 1e-2
        return np.array([x, v, x])

    def initial_state(self, drive_signal, t0: float):
        y0 = np.zeros(3)
        if self.drive == "velocity":
            y0[1] = float(drive_signal(t0))
        elif self.drive == "position":
            y0[0], y0[1] = drive_signal.evaluate(t0)
        return y0

    def channels(self, drive_signal):
        return [drive_signal, None, None, None, None]
