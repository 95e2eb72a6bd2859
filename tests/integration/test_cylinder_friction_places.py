"""Two friction laws on one cylinder (issue 41, item 1): ``Cylinder(params, friction=
{"piston": LuGre(), "rod": Dahl()})`` places each law as an instance of the kind friction
(``friction_piston.*``, ``friction_rod.*``), each with its own states; the rod feels their
sum. Known answers: in steady sliding the friction is the sum of the two laws' steady
curves at that speed and each state its own law's steady value; a batch equals single
runs; forward sensitivities to one parameter of each law against central differences; a
fit finds a rod parameter back from a simulated record; the C engine is numba's run. One
law keeps its unprefixed names and its kernel. One two-law model (one kernel) serves
the module."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.core.assembly import assemble
from pneumact.experiments import Experiment, PiecewiseLinear
from pneumact.parameters.catalogue import catalogue

pytestmark = pytest.mark.integration

#: held retracted, then the spool opened over 50 ms: the piston extends
MOVE = Experiment(PiecewiseLinear([0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3]), "spool",
                  0.3, n_points=301)
SIGNALS = ("position", "pressure_a", "pressure_b")
#: one parameter of each law, varied, differenced and fitted
VARIED = ("friction_piston.Fc", "friction_rod.Fc")


@pytest.fixture(scope="module")
def params():
    """The shipped set, its LuGre values on the piston, a Dahl law on the rod of half its
    Coulomb level and a quarter of its stiffness (its steady bristle deflection twice the
    piston's: the two states tell apart)."""
    base = load_quietly("iso15552-32")
    values = {f"friction_piston.{name}": base[name] for name in pa.LuGre().block.parameters}
    values.update({"friction_rod.sigma0": 0.25 * base["sigma0"],
                   "friction_rod.Fc": 0.5 * base["Fc"],
                   "friction_rod.sigma2": 0.3 * base["sigma2"],
                   "friction_rod.dahl_alpha": 1.0})
    return base.replace(values)


@pytest.fixture(scope="module")
def model(params):
    return pa.Cylinder(params, friction={"piston": pa.LuGre(), "rod": pa.Dahl()})


def test_each_law_is_an_instance_with_the_catalogue_entry_of_its_parameters(model, params):
    """friction_piston.* are LuGre's parameters, friction_rod.* Dahl's, each with the
    unprefixed parameter's unit and limits; their states are their own; one law keeps
    today's names and kernel (no instance, no placed-laws template)."""
    names = assemble(model).parameter_names
    assert [n for n in names if n.startswith("friction_piston.")] == [
        f"friction_piston.{n}" for n in pa.LuGre().block.parameters]
    assert [n for n in names if n.startswith("friction_rod.")] == [
        f"friction_rod.{n}" for n in pa.Dahl().block.parameters]
    assert "Fc" not in names
    entries = catalogue()
    for name in ("Fc", "sigma0", "dahl_alpha"):
        plain, placed = entries[name], entries[f"friction_rod.{name}"]
        assert (placed.unit, placed.default, placed.minimum, placed.maximum,
                placed.plausible) == (plain.unit, plain.default, plain.minimum,
                                      plain.maximum, plain.plausible)
    assert assemble(model).state_names[4:6] == ("friction_piston_bristle",
                                                "friction_rod_bristle")
    one = pa.Cylinder(params, pa.LuGre())
    assert "Fc" in one.required and not any(n.startswith("friction_") for n in one.required)
    assert "FRICTION_PISTON" not in assemble(one).kernel_spec().source()
    assert assemble(one).kernel_spec().children == ()


def test_steady_sliding_friction_is_the_sum_of_the_two_laws(model, params):
    """The spool held slightly open for 2 s: mid-stroke, where the piston's acceleration is
    least, the friction output is LuGre's Fc + (Fs − Fc)·e^(−(v/vs)^δ) + σ2·v at the
    piston's parameters plus Dahl's Fc + σ2·v at the rod's, and each bristle sits at its
    own law's steady deflection (g/σ0 and Fc/σ0: different)."""
    slow = Experiment(PiecewiseLinear([0.0, 0.05, 0.06, 2.0], [-1.0, -1.0, 0.05, 0.05]),
                      "spool", 2.0, n_points=2001)
    run = pa.simulate(model, slow, pa.Rodas4(rtol=ref.CYLINDER_RTOL))
    v, x = run["velocity"], run["position"]
    inside = np.flatnonzero((x > 0.1 * params["x_max"]) & (x < 0.9 * params["x_max"]))
    k = inside[np.argmin(np.abs(np.gradient(v, run.time)[inside]))]
    speed = v[k]
    assert speed > 10.0 * params["vs"], "the piston must slide for this test to bite"
    piston = {n: params[f"friction_piston.{n}"] for n in pa.LuGre().block.parameters}
    rod = {n: params[f"friction_rod.{n}"] for n in pa.Dahl().block.parameters}
    lugre = (piston["Fc"] + (piston["Fs"] - piston["Fc"])
             * np.exp(-((speed / piston["vs"]) ** piston["delta"])) + piston["sigma2"] * speed)
    dahl = rod["Fc"] + rod["sigma2"] * speed
    assert run["friction"][k] == pytest.approx(lugre + dahl,
                                               rel=ref.CYLINDER_PLACED_STEADY_RTOL)
    assert model.steady_friction(speed)[0] == pytest.approx(lugre + dahl, rel=1e-12)
    z_piston = (lugre - piston["sigma2"] * speed) / piston["sigma0"]
    z_rod = rod["Fc"] / rod["sigma0"]
    assert z_rod > 1.5 * z_piston
    assert run["friction_piston_bristle"][k] == pytest.approx(
        z_piston, rel=ref.CYLINDER_PLACED_STEADY_RTOL)
    assert run["friction_rod_bristle"][k] == pytest.approx(
        z_rod, rel=ref.CYLINDER_PLACED_STEADY_RTOL)


def test_a_batch_over_both_laws_equals_single_runs(model, params):
    """Rows of friction_rod.Fc and friction_piston.sigma2: each row's signals are those of
    a run of the set with those values."""
    fc, s2 = params["friction_rod.Fc"], params["friction_piston.sigma2"]
    table = pd.DataFrame({"friction_rod.Fc": [0.5 * fc, fc, 3.0 * fc],
                          "friction_piston.sigma2": [s2, 2.0 * s2, 0.5 * s2]})
    batch = pa.simulate_batch(model, MOVE, table, signals=list(SIGNALS),
                              t_eval=np.linspace(0.0, 0.3, 301), executor=1)
    assert list(batch.table["status"]) == ["ok"] * 3, batch.table["error"].tolist()
    for i, row in table.iterrows():
        run = pa.simulate(model, MOVE, t_eval=batch.time, values=row.to_dict())
        for signal in SIGNALS:
            np.testing.assert_allclose(batch.signals[signal][i], run[signal],
                                       rtol=ref.BATCH_FEATURE_RTOL, err_msg=(i, signal))
    assert np.ptp(batch.signals["position"][:, -1]) > 1e-4


def test_forward_sensitivities_to_each_law_match_differences(model, params):
    """∂(x, p_a, p_b)/∂ the piston's and the rod's Fc carried through the run against
    central differences of two runs given the value by name."""
    sens = pa.simulate_sensitivities(model, MOVE, list(VARIED), pa.Rodas4(rtol=ref.SENS_RTOL))
    tight = pa.Rodas4(rtol=ref.SENS_REFERENCE_RTOL)
    for column, name in enumerate(VARIED):
        assert sens.units[name] == "N"
        value = float(params[name])
        step = ref.SENS_FD_REL_STEP * value
        up, down = (pa.simulate(model, MOVE, tight, values={name: value + s})
                    for s in (step, -step))
        for signal in SIGNALS:
            difference = (up[signal] - down[signal]) / (2.0 * step)
            size = np.abs(difference).max()
            rms = np.sqrt(np.mean((sens[signal][:, column] - difference) ** 2))
            assert size > 0.0 and rms <= ref.SENS_RMS_FRACTION * size, (name, signal, rms,
                                                                         size)


def test_a_fit_finds_the_rod_s_coulomb_force(model, params):
    """friction_rod.Fc freed, started 30 % off, from the position of a simulated run."""
    run = pa.simulate(model, MOVE)
    record = pa.Record.from_arrays(run.time, {"position": run["position"],
                                              "spool": run["spool"]},
                                   {"position": "m", "spool": "1"}, "nominal")
    truth = float(params["friction_rod.Fc"])
    result = pa.fit(model, [record], ["friction_rod.Fc"],
                    start={"friction_rod.Fc": 1.3 * truth}, smooth_input=False)
    found = result.to_pandas()["value"]["friction_rod.Fc"]
    assert found == pytest.approx(truth, rel=ref.META_FIT_RTOL)


@pytest.mark.numba
def test_the_c_engine_runs_both_laws_as_numba(model):
    """The C back end translates the placed laws' child kernels with the rest: every
    signal as numba's (to ENGINE_AGREEMENT of its range)."""
    from pneumact.core.c_build import compiler_path

    if compiler_path() is None:
        pytest.skip("no C compiler")
    c = pa.simulate(model, MOVE, engine="c")
    numba = pa.simulate(model, MOVE, engine="numba")
    assert (c.meta["engine"], numba.meta["engine"]) == ("c", "numba")
    a, b = c.to_pandas().to_numpy(), numba.to_pandas().to_numpy()
    span = np.maximum(np.ptp(b, axis=0), np.finfo(float).tiny)
    assert np.max(np.abs(a - b) / span) <= ref.ENGINE_AGREEMENT


def test_unknown_places_and_names_are_refused_naming_the_allowed_ones(model, params):
    """A place the catalogue does not declare, a mapping missing one, a law that must be
    alone (GMS: its events are the model's) and an unknown instance's parameter are each
    refused with one message naming what is allowed."""
    with pytest.raises(pa.ArgumentError, match=r"'seal' is no place of a friction law; "
                                               r"places: 'piston', 'rod' \(instances "
                                               r"friction_piston, friction_rod\)"):
        pa.Cylinder(params, friction={"piston": pa.LuGre(), "seal": pa.Dahl()})
    with pytest.raises(pa.ArgumentError, match=r"a mapping places a law on each of "
                                               r"'piston', 'rod'"):
        pa.Cylinder(params, friction={"rod": pa.Dahl()})
    with pytest.raises(pa.ArgumentError, match=r"placed alone, not beside another law"):
        pa.Cylinder(params, friction={"piston": pa.LuGre(), "rod": pa.GMS()})
    with pytest.raises(pa.ParameterError, match=r"no component instance 'friction_seal'; "
                                                r"instances: .*friction_piston, friction_rod"):
        pa.simulate(model, MOVE, values={"friction_seal.Fc": 1.0})
    with pytest.raises(pa.ParameterError, match=r"'friction_piston.dahl_alpha' is not a "
                                                r"parameter of Cylinder"):
        pa.simulate(model, MOVE, values={"friction_piston.dahl_alpha": 1.0})


def test_linearised_at_rest_each_law_is_a_spring_of_its_own_stiffness(model, params):
    """At rest mid-stroke (v = 0, bristles undeflected) each law pulls on the velocity's row
    through its own state with its own stiffness, −σ0/m (LuGre's σ1 term vanishes with
    v), and the statement names the summed presliding stiffness; in steady sliding each
    state is its own law's steady deflection."""
    from pneumact.control import linearise

    plant = linearise(model, 0.0, position=0.1)
    row = plant.state_names.index("velocity")
    for instance in ("friction_piston", "friction_rod"):
        column = plant.state_names.index(f"{instance}_bristle")
        assert plant.A[row, column] == pytest.approx(
            -params[f"{instance}.sigma0"] / params["m"], rel=1e-12)
    stiffness = params["friction_piston.sigma0"] + params["friction_rod.sigma0"]
    assert f"presliding stiffness {stiffness:g} N/m" in plant.statement
    sliding = linearise(model, 0.0, position=0.1, regime="sliding", velocity=0.1)
    point = sliding.operating_point
    assert point["friction_rod_bristle"] == pytest.approx(
        params["friction_rod.Fc"] / params["friction_rod.sigma0"], rel=1e-12)
    assert point["friction_piston_bristle"] == pytest.approx(
        params["friction_piston.Fc"] / params["friction_piston.sigma0"], rel=1e-12)
