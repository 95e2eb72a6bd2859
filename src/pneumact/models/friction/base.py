"""What every friction law declares, and the pieces the laws share.

A friction law is a component with a parameter block, any number of internal states
(LuGre's bristle deflection; none for a static map) and compiled functions that work on
its slice of the state vector. The model templates (actuator, rig, the law on its own)
call only these slice-level functions, bound by the kernel generator under fixed names:

- ``friction_rates(v, y, s, p, o) -> (F, rates)`` and ``friction_store(rates, dydt, s)``:
  the friction force and the rates of the law's states ``y[s:s + N]``, stored into
  ``dydt[s:s + N]`` by the second function;
- ``friction_force(v, y, s, p, o) -> F``;
- ``friction_partials(v, y, s, p, o) -> (F, ∂F/∂v, partials)`` and
  ``friction_store_partials(partials, jac, s, col_v, row_f, mass)``: the second writes
  ``jac[s + i, s + j] = ∂ż_i/∂z_j``, ``jac[s + i, col_v] = ∂ż_i/∂v`` (``col_v >= 0``) and
  ``jac[row_f, s + j] = −∂F/∂z_j / mass`` (``row_f >= 0``: the friction decelerates the
  mass on that row);
- ``friction_param_partials(v, y, s, p, o, g, row_f)``: ``g[s + i, o + k] = ∂ż_i/∂p_k``
  and ``g[row_f, o + k] = ∂F/∂p_k`` for every entry k of the law's block;
- ``friction_project(p, o, y, s)``: back onto the set the exact dynamics never leave;
- ``friction_scales(p, o, out, s) -> (range, stiffness, v_reg)``: the typical magnitude
  of each state into ``out[s:s + N]``; the presliding range and stiffness and the
  regularisation speed (a static map's only scale).

``p`` is the whole parameter vector and ``o`` the offset of the law's block in it. The
rates and partials are returned as a value (a float, a tuple: whatever the law's own
store function takes) so that a template stores them *after* its last read of ``y`` and
``p``: the compiler cannot know that ``dydt`` does not alias them, and a store before
those reads makes it load them again (7 % on the pressure cycle). A law
with one state writes six scalar functions and uses the template ``scalar_law`` for the
slice; a law with no state uses ``stateless_law``; a law with element arrays (e.g.
Generalized Maxwell-Slip) provides its own template. On the numpy side every law answers
what analyses ask without a simulation: its steady-sliding force and states, its
presliding stiffness and range. The registry (``friction_models()``) finds every module
of this package, so a new law is one new module.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from ...core.component import Block, Part, StateSpec
from ...core.jit import njit
from ...parameters.catalogue import ParameterSpec, declare, declare_relation

__all__ = ["RELAXED_LEVEL", "SCALAR_LAW", "STATELESS_LAW", "CoulombBristleLaw", "FrictionModel",
           "StribeckBristleLaw", "clear_block",
           "power", "presliding_scale", "sign", "stribeck_curve", "stribeck_curve_params"]

P = ParameterSpec
declare(
    P("sigma0", "N/m", "bristle stiffness", None, 0.0, True, 1e12, group="friction",
      plausible=(10.0, 1e10)),
    P("sigma1", "N*s/m", "bristle (micro-)damping", 0.0, 0.0, False, 1e8, group="friction",
      plausible=(0.0, 1e6)),
    P("sigma2", "N*s/m", "viscous friction coefficient (the only viscous term)", 0.0, 0.0,
      False, 1e8, group="friction", plausible=(0.0, 1e6)),
    P("Fc", "N", "Coulomb friction force (0: frictionless)", None, 0.0, False, 1e7,
      group="friction", plausible=(0.0, 1e5)),
    P("Fs", "N", "static (break-away) friction force, Fs >= Fc", None, 0.0, False, 1e7,
      group="friction", plausible=(0.0, 1e5)),
    P("vs", "m/s", "Stribeck velocity", None, 0.0, True, 100.0, group="friction",
      plausible=(1e-7, 1.0)),
    P("delta", "", "Stribeck exponent (paper eq. 8: 1; usual LuGre: 2)", 2.0, 0.0, True,
      100.0, group="friction", plausible=(0.2, 5.0)),
    P("v_reg", "m/s", "sign regularisation velocity of the static friction maps", 1e-4, 0.0,
      True, 10.0, group="friction", plausible=(1e-9, 0.1)),
)
declare_relation(("Fs", "Fc"), lambda fs, fc: fs >= fc,
                 lambda fs, fc: f"must be >= Fc = {fc:g} N (static friction is at least "
                                "the Coulomb friction)")

#: Friction level g(v) below this fraction of Fs counts as none: the bristles then relax
#: within g/(σ0·|v|), attoseconds, far below any step, and the law takes its limit.
RELAXED_LEVEL = 1e-12

#: kernel templates of the slice-level functions for laws of one state and of none
SCALAR_LAW = "pneumact.models.friction.scalar_law"
STATELESS_LAW = "pneumact.models.friction.stateless_law"


@njit(cache=True)
def sign(v):  # pragma: no cover - compiled
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@njit(cache=True, inline="always")
def power(a, exponent):  # pragma: no cover - compiled
    """a**exponent, without a pow() call for the exponents 1 and 2 (the paper's δ, and
    Canudas de Wit's): the Stribeck curve is evaluated at every stage of every step."""
    if exponent == 1.0:
        return a
    if exponent == 2.0:
        return a * a
    return a**exponent


@njit(cache=True)
def stribeck_curve(v, fc, fs, vs, delta):  # pragma: no cover - compiled
    """g(v) = Fc + (Fs − Fc)·exp(−(|v|/vs)^δ) and its derivative dg/dv."""
    ds = fs - fc
    a = abs(v) / vs
    if a == 0.0:
        return fc + ds, 0.0
    ad = power(a, delta)
    e = math.exp(-ad)
    return fc + ds * e, -ds * e * delta * ad / a * sign(v) / vs


@njit(cache=True)
def stribeck_curve_params(v, fc, fs, vs, delta):  # pragma: no cover - compiled
    """g(v) and its derivatives (∂g/∂Fc, ∂g/∂Fs, ∂g/∂vs, ∂g/∂δ)."""
    a = abs(v) / vs
    if a == 0.0:
        return fs, 0.0, 1.0, 0.0, 0.0
    ad = power(a, delta)
    e = math.exp(-ad)
    ds = fs - fc
    return fc + ds * e, 1.0 - e, e, ds * e * delta * ad / vs, -ds * e * ad * math.log(a)


def stribeck_level(speed, params) -> np.ndarray:
    """g(|v|) of the parameter set, on arrays (numpy twin of ``stribeck_curve``)."""
    speed = np.abs(np.asarray(speed, dtype=float))
    return params["Fc"] + (params["Fs"] - params["Fc"]) * np.exp(
        -((speed / params["vs"]) ** params["delta"]))


@njit(cache=True)
def presliding_scale(level, s0):  # pragma: no cover - compiled
    """Typical bristle deflection level/σ0; with no friction level (a frictionless law,
    whose z stays 0) the deflection under 1 N, so the tolerance on z stays positive."""
    return (level if level > 0.0 else 1.0) / s0


@njit(cache=True)
def clear_block(g, rz, rf, o, size):  # pragma: no cover - compiled
    """Zero the rows ``rz`` and ``rf`` of ``g`` over a law's block."""
    for k in range(size):
        g[rz, o + k] = 0.0
        g[rf, o + k] = 0.0


_BY_CLI_NAME: dict[str, type[FrictionModel]] = {}


class FrictionModel:
    """A friction law: its parameters, its states, its compiled functions, and the
    steady-sliding and presliding facts every analysis asks of it.

    A law of one state sets ``block`` (its parameters, in the order its functions read
    them), ``law`` (the base name of its six compiled functions in its module: ``law``,
    ``law_params``, ``law_scales``, ``law_bound``) and ``cli_name`` (its ``--friction``
    choice); a law of another shape overrides ``states``, ``template`` and
    ``functions()``. The numpy side (``steady_states``, ``presliding_stiffness``,
    ``presliding_range``) is the law's own; ``steady_force`` and ``evaluate`` follow.
    """

    block: ClassVar[Block]
    law: ClassVar[str]
    cli_name: ClassVar[str]
    states: ClassVar[tuple[StateSpec, ...]] = (StateSpec("bristle", "m", monotone=True),)
    template: ClassVar[str] = SCALAR_LAW
    #: the compiled functions the template binds: ``law`` + each suffix
    compiled: ClassVar[tuple[str, ...]] = ("", "_params", "_scales", "_bound")
    #: why a run of the law cannot carry forward sensitivities (None: it can)
    sensitivity_refusal: ClassVar[str | None] = None
    #: why the law cannot share a body with another law placed beside it (None: it can;
    #: ``placed_laws``): a law whose template holds model-level functions (events)
    placed_alone: ClassVar[str | None] = None

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "cli_name" in cls.__dict__:
            _BY_CLI_NAME[cls.cli_name] = cls

    @property
    def required(self) -> tuple[str, ...]:
        """The parameters this law reads."""
        return self.block.parameters

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(state.name for state in self.states)

    @property
    def kernel(self) -> str:
        """Name of the law's compiled variant (part of the kernel's key)."""
        return self.law

    def functions(self) -> dict[str, str]:
        """What the law's template calls -> "module:function" of the law's module."""
        module = type(self).__module__
        return {f"friction_law{suffix}": f"{module}:{self.law}{suffix}"
                for suffix in self.compiled}

    def part(self) -> Part:
        return Part(role="friction", block=self.block, states=tuple(self.states),
                    functions=self.functions(), templates=(self.template,),
                    label=repr(self), key=self.law)

    # -- what the law says without a simulation (numpy) ---------------------------------
    def steady_states(self, v, params) -> np.ndarray:
        """The law's states in steady sliding at velocities ``v``: shape (len(v), N)."""
        raise NotImplementedError

    def presliding_stiffness(self, params) -> float:
        """∂F/∂x at rest (N/m): the stiffness the body feels before it slides."""
        raise NotImplementedError

    def presliding_range(self, params) -> float:
        """How far the body moves at rest before gross sliding (m); 0 for a static map.
        With no friction level (frictionless) the deflection under 1 N."""
        raise NotImplementedError

    #: block parameters a comparison of laws leaves at the set's values: shape exponents
    #: and regularisations that trade off with the others and say little of the law
    held_in_comparison: ClassVar[tuple[str, ...]] = ("delta", "v_reg")

    #: narrower search ranges a comparison keeps a parameter in than its plausible range
    #: (a shape exponent whose low end makes runs of millions of steps)
    comparison_ranges: ClassVar[dict[str, tuple[float, float]]] = {}

    def comparison_parameters(self) -> tuple[str, ...]:
        """The parameters ``compare_friction_models`` fits for this law."""
        return tuple(n for n in self.block.parameters if n not in self.held_in_comparison)

    def matched_values(self, params) -> dict[str, float]:
        """Values of the law's own parameters that match a LuGre set (its σ0, Fc, Fs, vs),
        for a set that lacks them: a starting point to fit from, not a measurement. Laws
        whose own parameters have catalogue defaults return none."""
        return {}

    def relaxation_length(self, v, params) -> np.ndarray:
        """Sliding distance over which the states settle at speed |v| (m); its ratio to
        the speed is the law's time constant there (0 for a static map)."""
        states = self.steady_states(np.abs(np.atleast_1d(np.asarray(v, float))), params)
        return np.abs(states).max(axis=1) if states.shape[1] else np.zeros(states.shape[0])

    def steady_force(self, v, params) -> np.ndarray:
        """Friction force in steady sliding at velocities ``v`` (the states at rest)."""
        v = np.atleast_1d(np.asarray(v, dtype=np.float64))
        return self.evaluate(v, self.steady_states(v, params), params)["force"]

    # -- the compiled law at arrays (tests, plots, identification) -----------------------
    def evaluate(self, v, y, params) -> dict[str, np.ndarray]:
        """The law at velocities ``v`` (n,) and states ``y`` (n, N), or a scalar state
        broadcast: ``force``, ``dforce_dv`` (n,); ``rates``, ``drates_dv``, ``dforce_dy``
        (n, N); ``drates_dy`` (n, N, N)."""
        from .evaluation import friction_law_values

        return friction_law_values(self, v, y, params)

    def parameter_derivatives(self, v, y, params) -> dict[str, np.ndarray]:
        """Parameter name -> (n, N + 1) array: ∂ż_i/∂θ for each state, then ∂F/∂θ."""
        from .evaluation import friction_law_parameter_derivatives

        return friction_law_parameter_derivatives(self, v, y, params)

    @property
    def name(self) -> str:
        return type(self).__name__

    @property
    def spec(self) -> str:
        """The law as ``friction_law`` reads it ("lugre", "gms:4"): a short label."""
        return self.cli_name

    def __repr__(self) -> str:
        return f"{self.name}()"

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and repr(self) == repr(other)

    def __hash__(self) -> int:
        return hash(repr(self))


class CoulombBristleLaw(FrictionModel):
    """A law of one bristle state that settles at z = sgn(v)·Fc/σ0 in steady sliding
    (Dahl, Bouc-Wen): stiffness σ0, presliding range Fc/σ0."""

    def steady_states(self, v, params) -> np.ndarray:
        v = np.atleast_1d(np.asarray(v, dtype=float))
        return (np.sign(v) * params["Fc"] / params["sigma0"])[:, None]

    def presliding_stiffness(self, params) -> float:
        return float(params["sigma0"])

    def presliding_range(self, params) -> float:
        level = float(params["Fc"])
        return (level if level > 0.0 else 1.0) / float(params["sigma0"])


class StribeckBristleLaw(FrictionModel):
    """A law of one bristle state that settles at z = sgn(v)·g(v)/σ0 in steady sliding, g
    the Stribeck curve (LuGre, elasto-plastic): stiffness σ0, range max(Fs, Fc)/σ0."""

    def steady_states(self, v, params) -> np.ndarray:
        """z = sgn(v)·g(v)/σ0: the bristle deflection where dz/dt = 0."""
        v = np.atleast_1d(np.asarray(v, dtype=float))
        return (np.sign(v) * stribeck_level(v, params) / params["sigma0"])[:, None]

    def presliding_stiffness(self, params) -> float:
        return float(params["sigma0"])

    def presliding_range(self, params) -> float:
        level = max(float(params["Fs"]), float(params["Fc"]))
        return (level if level > 0.0 else 1.0) / float(params["sigma0"])


def registered() -> dict[str, type[FrictionModel]]:
    """Command-line name -> class of every law defined so far."""
    return dict(_BY_CLI_NAME)
