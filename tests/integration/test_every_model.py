"""Every model kind through every entry point (issue 41, item 5).

Each pair of a model kind (the diaphragm actuator, the force-driven friction rig, the
double-acting cylinder, the cylinder in a closed loop) and an entry point (simulate, the
batch engine, forward sensitivities, fit, a global sensitivity method, linearisation, the
FMU export) either works, with a check that can fail (a batch row is the single run's
summary, sensitivities are central differences, a fit finds the parameters that made its
record, ...), or is refused with one clear error, which ``REFUSED`` states and the test
checks; a pair that does neither fails. The runs are short and reuse the kernels the
other tests compile (the cylinder loop's sensitivities excepted: nothing else needs them).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact import sensitivity as sa
from pneumact.control import PID, ClosedLoop, linearise
from pneumact.core.features import FEATURE_UNITS
from pneumact.experiments import Experiment, PiecewiseLinear, SetpointRamp
from pneumact.simulation.simulate import Model

pytestmark = pytest.mark.integration

#: the friction parameters every kind has (its LuGre law's): varied, fitted, differenced
#: (a Coulomb level, then a viscous coefficient; the two-law cylinder's are its laws')
VARIED = ("Fc", "sigma2")
ENTRY_POINTS = ("simulate", "simulate_batch", "sensitivities", "fit", "src", "linearise",
                "export_fmu")
#: the pairs refused, with the error and what its message must say
REFUSED = {
    ("loop", "linearise"): (pa.ParameterError, r"linearise: plant = ClosedLoop.*allowed: an "
                                               r"Actuator, a Cylinder"),
    ("rig", "export_fmu"): (pa.ArgumentError, r"model = FrictionRig; an FMU is exported "
                                              r"from a pa.Actuator or a pa.Cylinder"),
    ("loop", "export_fmu"): (pa.ArgumentError, r"model = ClosedLoop; an FMU is exported "
                                               r"from a pa.Actuator or a pa.Cylinder"),
    ("two_valves", "linearise"): (pa.ParameterError, r"linearise: plant = Cylinder\(.*"
                                                     r"valves='two-3/2'\); allowed: .*a "
                                                     r"Cylinder fed by its 5/3 valve"),
}


@dataclass(frozen=True, eq=False)
class Case:
    """A model kind with its experiment (inputs linear between samples, so that a record
    of the run drives the model exactly as the experiment did), the feature its global
    sensitivity study reads, and its linearisation point (input, position or None)."""

    model: Model
    experiment: Experiment
    feature: str
    input_value: float
    position: float | None
    varied: tuple[str, str] = VARIED


#: the PID of the cylinder's loop tests
PID_GAINS = {"kp": 60.0, "ki": 300.0, "kd": 0.5}


def _cylinder_loop(cylinder, bias: float = 0.0) -> ClosedLoop:
    return ClosedLoop(cylinder, PID(**PID_GAINS, derivative="velocity", u_min=-1.0,
                                    u_max=1.0), bias=bias)


def _make(kind: str) -> Case:
    if kind == "actuator":
        return Case(pa.Actuator(load_quietly("vgt-paper")),
                    pa.PressureCycle(high=100e3, low=20e3, period=2.0, n_points=201),
                    "loop_width_pressure", 60e3, None)
    if kind == "rig":  # pushed one way, then the other
        force = PiecewiseLinear([0.0, 0.25, 0.75, 1.0], [0.0, 2.0, -2.0, 0.0])
        return Case(pa.FrictionRig(load_quietly("canudas1995"), drive="force"),
                    Experiment(force, "force", 1.0, n_points=201), "position_range", 0.0,
                    None)
    cylinder = pa.Cylinder(load_quietly("iso15552-32"))
    if kind == "cylinder":  # held retracted, the spool opened over 50 ms: it extends;
        # linearised mid-stroke at the spool command that balances the chambers there
        spool = PiecewiseLinear([0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3])
        return Case(cylinder, Experiment(spool, "spool", 0.3, n_points=301),
                    "top_speed_out", _cylinder_loop(cylinder).holding_input(0.1), 0.1)
    if kind == "two_valves":  # as "cylinder", through a 3/2 valve per chamber: u_b = -u_a
        model = pa.Cylinder(load_quietly("iso15552-32"), valves="two-3/2")
        times, command = [0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3]
        drives = {"command_b": PiecewiseLinear(times, [-u for u in command])}
        return Case(model, Experiment(PiecewiseLinear(times, command), "command_a", 0.3,
                                      n_points=301, drives=drives),
                    "top_speed_out", 0.0, 0.1)
    if kind == "mirrored":  # as "cylinder": two 3/2 valves driven by one command u,
        # u_a = u and u_b = -u; linearised where its own loop holds it
        model = pa.Cylinder(load_quietly("iso15552-32"), valves="two-3/2", mirrored=True)
        spool = PiecewiseLinear([0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3])
        return Case(model, Experiment(spool, "spool", 0.3, n_points=301), "top_speed_out",
                    _cylinder_loop(model).holding_input(0.1), 0.1)
    if kind == "two_laws":  # as "cylinder", LuGre on the piston and Dahl on the rod;
        # linearised at the one-law cylinder's holding command (friction at rest carries
        # no force: the chambers alone balance)
        params = load_quietly("iso15552-32")
        values = {f"friction_piston.{n}": params[n] for n in pa.LuGre().block.parameters}
        values.update({f"friction_rod.{n}": params[n] for n in ("sigma0", "Fc", "sigma2")})
        model = pa.Cylinder(params.replace({**values, "friction_rod.dahl_alpha": 1.0}),
                            friction={"piston": pa.LuGre(), "rod": pa.Dahl()})
        spool = PiecewiseLinear([0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3])
        return Case(model, Experiment(spool, "spool", 0.3, n_points=301), "top_speed_out",
                    _cylinder_loop(cylinder).holding_input(0.1), 0.1,
                    ("friction_rod.Fc", "friction_piston.sigma2"))
    # held at 90 mm, then a 20 mm ramp over 50 ms
    return Case(_cylinder_loop(cylinder, _cylinder_loop(cylinder).holding_input(0.09)),
                SetpointRamp(0.09, 0.11, 0.05, t_start=0.05, t_end=0.5, n_points=501),
                "top_speed_out", 0.0, None)


KINDS = ("actuator", "rig", "cylinder", "two_valves", "mirrored", "two_laws", "loop")


@pytest.fixture(scope="module")
def cases() -> dict[str, Case]:
    return {}


@pytest.fixture
def case(cases, request) -> Case:
    kind = request.param
    if kind not in cases:
        cases[kind] = _make(kind)
    return cases[kind]


def test_every_model_kind_is_walked():
    """The kinds above are every model of the package: each public class that the
    ``Model`` protocol describes (its instances pass ``check_model``)."""
    import pneumact.control
    import pneumact.models

    modules = (pneumact.models, pneumact.control)
    classes = [getattr(m, name) for m in modules for name in m.__all__]
    models = {c for c in classes if isinstance(c, type) and all(
        hasattr(c, a) for a in ("parts", "channels", "breakpoints", "driven_by"))}
    walked = {type(_make(kind).model) for kind in KINDS}
    assert models == walked, f"walk these too: {sorted(c.__name__ for c in models - walked)}"


# ------------------------------------------------------------------------ the checks
def _simulate(case: Case, tmp_path) -> None:
    """The run's summary: the model's features, finite, each a batch feature."""
    summary = pa.simulate(case.model, case.experiment).summary()
    assert set(summary) <= set(FEATURE_UNITS), sorted(set(summary) - set(FEATURE_UNITS))
    assert all(np.isfinite(v) for v in summary.values()), summary


def _simulate_batch(case: Case, tmp_path) -> None:
    """The nominal row's default features are the single run's summary; a changed Fc
    changes them."""
    coulomb = case.varied[0]
    fc = float(case.model.params[coulomb])
    batch = pa.simulate_batch(case.model, case.experiment,
                              pd.DataFrame({coulomb: [fc, 1.2 * fc]}), executor=1)
    assert list(batch.table["status"]) == ["ok", "ok"], batch.table["error"].tolist()
    summary = pa.simulate(case.model, case.experiment).summary()
    shared = [name for name in summary if name in batch.table]
    assert shared and set(shared) == set(summary)  # every summary feature is in the batch
    nominal = batch.table.iloc[0]
    for name in shared:
        np.testing.assert_allclose(nominal[name], summary[name], rtol=ref.META_BATCH_RTOL,
                                   err_msg=name)
    changed = batch.table.iloc[1]
    assert any(changed[n] != nominal[n] for n in shared)


def _sensitivities(case: Case, tmp_path) -> None:
    """∂position/∂θ against central differences (RMS within a fraction of its size, or
    within the differences' own noise)."""
    tight = pa.Rodas4(rtol=ref.SENS_REFERENCE_RTOL)
    sens = pa.simulate_sensitivities(case.model, case.experiment, list(case.varied),
                                     pa.Rodas4(rtol=ref.SENS_RTOL))
    travel = float(np.ptp(sens.result["position"]))
    for k, name in enumerate(case.varied):
        value = float(case.model.params[name])
        step = ref.SENS_FD_REL_STEP * value
        up, down = (pa.simulate(case.model, case.experiment, tight,
                                values={name: value + s})["position"] for s in (step, -step))
        difference = (up - down) / (2.0 * step)
        rms = np.sqrt(np.mean((sens["position"][:, k] - difference) ** 2))
        noise = ref.META_SENS_NOISE_FACTOR * ref.SENS_REFERENCE_RTOL * travel / step
        allowed = max(ref.SENS_RMS_FRACTION * np.max(np.abs(difference)), noise)
        assert rms <= allowed, (name, rms, allowed)


def _record(case: Case):
    """The nominal run as a record: its position, the signal that drives the model and
    those of the inputs beside it that the experiment drives (their record signals)."""
    run = pa.simulate(case.model, case.experiment)
    drive = case.model.input_signal
    values = run[drive] if drive in run else run[f"drive_{case.experiment.quantity}"]
    signals, units = {"position": run["position"], drive: values}, {"position": "m",
                                                                     drive: case.experiment.unit}
    for name in case.experiment.drives:
        declared = case.model.declared_input(name, "the record")
        signals[declared.record_signal] = run[declared.record_signal]
        units[declared.record_signal] = declared.unit
    return pa.Record.from_arrays(run.time, signals, units, "nominal")


def _fit(case: Case, tmp_path) -> None:
    """Started 30 % off, the fit finds the Fc and σ2 that made its record."""
    coulomb, viscous = case.varied
    truth = {name: float(case.model.params[name]) for name in case.varied}
    result = pa.fit(case.model, [_record(case)], list(case.varied),
                    start={coulomb: 1.3 * truth[coulomb], viscous: 0.7 * truth[viscous]},
                    smooth_input=False)
    found = result.to_pandas()["value"]
    for name, value in truth.items():
        assert found[name] == pytest.approx(value, rel=ref.META_FIT_RTOL), name


def _src(case: Case, tmp_path) -> None:
    """Standardised regression coefficients of the kind's feature on ±5 % of Fc and σ2:
    a near-linear response (R²), and Fc's coefficient has the sign of the feature's change
    with Fc."""
    problem = sa.Problem.around(case.model.params, dict.fromkeys(case.varied, 0.05))
    evaluate = sa.model_outputs(case.model, case.experiment, problem, [case.feature],
                                executor=1)
    study = sa.src(problem, evaluate, n=ref.META_SRC_N, seed=1)
    indices = study.indices.set_index("parameter")
    assert indices["R2"].iloc[0] >= ref.META_SRC_R2_MIN, indices
    coulomb = case.varied[0]
    fc = float(case.model.params[coulomb])
    ends = pa.simulate_batch(case.model, case.experiment,
                             pd.DataFrame({coulomb: [0.95 * fc, 1.05 * fc]}),
                             features=[case.feature], executor=1).table[case.feature]
    assert np.sign(indices.loc[coulomb, "SRC"]) == np.sign(ends.iloc[1] - ends.iloc[0])


def _linearise(case: Case, tmp_path) -> None:
    """A rest with friction: an equilibrium (no rates) whose modes decay or stay."""
    plant = linearise(case.model, case.input_value, position=case.position)
    assert plant.equilibrium and plant.output_names == ("position",)
    scales = np.where(plant.state_scales > 0, plant.state_scales, 1.0)
    assert np.max(np.abs(plant.rates) / scales) <= ref.META_REST_RATE, plant.rates
    eigenvalues = np.linalg.eigvals(plant.A)
    assert np.all(eigenvalues.real <= ref.META_EIGEN_RTOL * np.max(np.abs(eigenvalues)))


def _export_fmu(case: Case, tmp_path) -> None:
    """The FMU (sources only) has the inputs the model declares and its position."""
    fmu = pa.export_fmu(case.model, tmp_path / "model.fmu", binary=False)
    declared = tuple(i.name for i in case.model.fmu_interface().inputs)
    assert fmu.names("input") == declared
    assert "position" in fmu.names("output")


CHECKS = {"simulate": _simulate, "simulate_batch": _simulate_batch,
          "sensitivities": _sensitivities, "fit": _fit, "src": _src,
          "linearise": _linearise, "export_fmu": _export_fmu}


@pytest.mark.parametrize(("case", "entry_point"), list(itertools.product(KINDS, ENTRY_POINTS)),
                         indirect=["case"])
def test_every_entry_point_works_or_refuses(case, entry_point, request, tmp_path):
    kind = request.node.callspec.params["case"]
    refused = REFUSED.get((kind, entry_point))
    if refused is None:
        CHECKS[entry_point](case, tmp_path)
        return
    error, message = refused
    with pytest.raises(error, match=message):
        CHECKS[entry_point](case, tmp_path)


#: per model (and valve), a drive its components refuse, and what the refusal says
BAD_DRIVES = {
    "source": ("pressure", -5e3, r"its pressure = -5000 Pa: an absolute pressure must be in"),
    "command": ("command", 1.5, r"its command spans 0 to 1.5; a valve command must stay "
                                r"within \[0, 1\]"),
    "regulator": ("pressure", 0.0, r"its pressure = 0 Pa"),
    "cylinder": ("spool", 1.5, r"its spool command spans 0 to 1.5; a 5/3 valve's command "
                               r"must stay within \[-1, 1\]"),
    "loop": ("position", 0.25, r"its set-point spans 0 to 250 mm; the actuator's stroke is "
                               r"0 to x_max"),
}


def _ramp_to(quantity: str, value: float) -> Experiment:
    start = 1e5 if quantity == "pressure" else 0.0
    return Experiment(PiecewiseLinear([0.0, 0.1], [start, value]), quantity, 0.1)


@pytest.mark.parametrize("kind", list(BAD_DRIVES))
def test_each_model_refuses_the_drives_its_components_cannot_take(kind):
    """The limits and the message are the model's (``check_drive_values``: the valve's, the
    5/3 valve's, the loop's stroke), not a list of quantities in ``simulation``; the rig
    takes any force."""
    from pneumact.simulation.simulate import check_drive

    valves = {"source": pa.PressureSource(), "command": pa.CommandValve(),
              "regulator": pa.PressureRegulator()}
    if kind in valves:
        model = pa.Actuator(load_quietly("vgt-paper"), valve=valves[kind])
    else:
        model = _make(kind).model
    quantity, value, message = BAD_DRIVES[kind]
    with pytest.raises(pa.ExperimentError, match=message):
        check_drive(model, _ramp_to(quantity, value))
    check_drive(_make("rig").model, _ramp_to("force", 1e6))


# ------------------------------------------------- inputs declared by the model (item 2)
def _declaring_models() -> dict[str, Model]:
    """Every model kind with each of its components that owns an input: the actuator
    behind each valve (and declaring its load), the rig with each drive, the cylinder, a
    loop around the cylinder (a stroke) and around the force rig (none)."""
    from pneumact.models import VALVES
    from pneumact.models.actuator import LOAD_INPUT
    from pneumact.models.rig import DRIVES

    vgt, canudas = load_quietly("vgt-paper"), load_quietly("canudas1995")
    cylinder = pa.Cylinder(load_quietly("iso15552-32"))
    force_rig = pa.FrictionRig(canudas, drive="force")
    return {**{f"actuator-{name}": pa.Actuator(vgt, valve=cls())
               for name, cls in VALVES.items()},
            "actuator-load": pa.Actuator(vgt, load=LOAD_INPUT),
            **{f"rig-{drive}": pa.FrictionRig(canudas, drive=drive) for drive in DRIVES},
            "cylinder": cylinder, "cylinder-two-3/2": _make("two_valves").model,
            "loop-cylinder": _cylinder_loop(cylinder),
            "loop-rig": ClosedLoop(force_rig, PID(kp=1.0))}


#: per model, the range its drive declares (None: the plant's stroke, 0 to x_max)
DECLARED_RANGES = {
    "actuator-source": (1e3, 10e6), "actuator-regulator": (1e3, 10e6),
    "actuator-command": (0.0, 1.0), "actuator-iso6358": (0.0, 1.0),
    "actuator-load": (1e3, 10e6),
    "rig-force": (-np.inf, np.inf), "rig-spring": (-np.inf, np.inf),
    "rig-velocity": (-np.inf, np.inf), "rig-position": (-np.inf, np.inf),
    "cylinder": (-1.0, 1.0), "cylinder-two-3/2": (-1.0, 1.0), "loop-cylinder": None,
    "loop-rig": (-np.inf, np.inf),
}


def _span_to(start: float, value: float, quantity: str) -> Experiment:
    """An experiment of ``quantity`` from ``start`` to ``value``: its extremes."""
    return Experiment(PiecewiseLinear([0.0, 0.1], [start, value]), quantity, 0.1)


def _inside_and_outside(end: float, upper: bool) -> tuple[float, float]:
    step = ref.INPUT_EDGE_REL * max(abs(end), 1.0)
    return (end - step, end + step) if upper else (end + step, end - step)


def test_the_model_kinds_are_those_declaring_inputs():
    """Each kind of ``KINDS`` is among the models whose declared inputs are checked."""
    declaring = {type(model) for model in _declaring_models().values()}
    assert declaring == {type(_make(kind).model) for kind in KINDS}
    assert set(DECLARED_RANGES) == set(_declaring_models())


@pytest.mark.parametrize("name", list(DECLARED_RANGES))
def test_every_model_declares_its_inputs_and_enforces_their_ranges(name):
    """The protocol's drive questions read the one declaration (name, unit, range, record
    signal); a drive just inside its declared range passes ``check_drive``, just outside
    it is refused, at each finite end; an unbounded one takes any value; an experiment of
    a quantity the model does not declare is refused naming it, the model and its
    inputs; each input beside the drive (the cylinder's load and supply pressure), driven
    by name, likewise (from zero or its range's nearest end),
    and reaches its channel."""
    from pneumact.core.channels import InputChannel
    from pneumact.experiments import QUANTITIES
    from pneumact.simulation.simulate import check_drive

    model = _declaring_models()[name]
    declared = model.inputs()
    assert declared and all(isinstance(c, InputChannel) for c in declared)
    drive = declared[0]
    assert (model.drive_quantity, model.drive_unit) == (drive.name, drive.unit)
    assert drive.unit == QUANTITIES[drive.name]  # one unit per quantity, the declared one
    assert model.input_signal == drive.record_signals[0]
    assert model.input_signal in model.input_signals
    low, high = DECLARED_RANGES[name] or (0.0, model.params["x_max"])
    assert (drive.low, drive.high) == (low, high)
    span = model.input_range
    assert span == drive.span and low <= span[0] < span[1] <= high
    start = 0.5 * (span[0] + span[1]) if np.isfinite(span).all() else 0.0
    for end, upper in ((low, False), (high, True)):
        if not np.isfinite(end):
            check_drive(model, _span_to(start, np.copysign(ref.INPUT_UNBOUNDED_PROBE, end),
                                        drive.name))
            continue
        inside, outside = _inside_and_outside(end, upper)
        check_drive(model, _span_to(start, inside, drive.name))
        model.check_drive_values(min(start, inside), max(start, inside), "probe")
        with pytest.raises(pa.ExperimentError, match=f"its {drive.label}"):
            check_drive(model, _span_to(start, outside, drive.name))
        with pytest.raises(pa.ExperimentError, match="probe"):
            model.check_drive_values(min(start, outside), max(start, outside), "probe")
    other = next(q for q in QUANTITIES if q not in {c.name for c in declared})
    with pytest.raises(pa.ExperimentError, match=(
            rf"drives '{other}', but the .* of this {type(model).__name__} needs a "
            rf"'{drive.name}' signal \(its declared inputs: '{drive.name}' \[")):
        check_drive(model, _span_to(1e5, 1e5, other))
    for beside in declared[1:]:
        _check_input_beside_the_drive(model, beside, _span_to(start, start, drive.name))


def _check_input_beside_the_drive(model, declared, held: Experiment) -> None:
    """An input beside the drive (``held``, at rest mid-range), driven by name: just
    inside its declared range it passes ``check_drive`` and reaches the channel it
    declares, just outside it is refused naming it; as the experiment's quantity it is
    refused naming the model's drive."""
    from pneumact.simulation.simulate import check_drive

    rest = min(max(0.0, declared.low), declared.high)  # zero, or its range's nearest end

    def driving(value: float) -> Experiment:
        signal = PiecewiseLinear([0.0, 0.1], [rest, value])
        return Experiment(held.drive, held.quantity, 0.1, drives={declared.name: signal})

    for end, upper in ((declared.low, False), (declared.high, True)):
        assert np.isfinite(end), f"{declared.name}: an input beside the drive is bounded"
        inside, outside = _inside_and_outside(end, upper)
        check_drive(model, driving(inside))
        with pytest.raises(pa.ExperimentError, match=f"its {declared.label} spans"):
            check_drive(model, driving(outside))
    signal = driving(declared.high).drives[declared.name]
    channels = model.channels(held.drive, {declared.name: signal})
    assert channels[model.channel_names.index(declared.channel)] is signal
    with pytest.raises(pa.ExperimentError, match=f"but the drive of this {type(model).__name__}"
                                                 f" is '{held.quantity}'"):
        check_drive(model, Experiment(signal, declared.name, 0.1,
                                      drives={held.quantity: held.drive}))


def test_each_valve_declares_its_own_input():
    """The component that owns an input declares it: a valve's ``drive`` and
    ``input_signal`` are its declaration's, and an actuator's input is its valve's."""
    from pneumact.models import VALVES

    vgt = load_quietly("vgt-paper")
    for cls in VALVES.values():
        assert (cls.drive, cls.input_signal) == (cls.declared.name,
                                                 cls.declared.record_signal)
        assert pa.Actuator(vgt, valve=cls()).inputs() == (cls().declared_input(vgt),)
    regulator = pa.PressureRegulator().declared_input(vgt)
    assert regulator.span == (vgt["p_res"], vgt["p_atm"])  # acts there, clips beyond
