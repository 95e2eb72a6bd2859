"""Presentation (issue #42). Figures that scale: a figure of many records is a grid of
readable panels (at most ``MAX_PANEL_COLUMNS`` side by side, wrapping into rows), never
one long row; log axes are labelled with numbers. Units a person reads: mm or µm, kPa."""

from __future__ import annotations

import io
import os

import numpy as np
import pandas as pd
import pytest
from PIL import Image
from typer.testing import CliRunner

import reference as ref
from pneumact import plotting
from pneumact.cli import app
from pneumact.identification import paper_campaign, synthetic_campaign

runner = CliRunner()


@pytest.fixture
def drawn(monkeypatch):
    """Every figure drawn as PNG (to a file or to a report's bytes): its width and its
    visible axes' widths in pixels at the dpi it was drawn at."""
    from matplotlib.figure import Figure

    import pneumact.plotting

    seen: list[tuple[str, float, list[float]]] = []
    savefig, tight_png = Figure.savefig, pneumact.plotting._tight_png

    def record(fig, name: str, dpi) -> None:
        scale = (dpi or fig.dpi) / fig.dpi
        widths = [ax.get_window_extent().width * scale for ax in fig.axes
                  if ax.get_visible()]
        seen.append((name, fig.get_figwidth() * (dpi or fig.dpi), widths))

    def spy(fig, target, *args, dpi=None, **kw):
        savefig(fig, target, *args, dpi=dpi, **kw)
        record(fig, str(getattr(target, "name", target)) if not hasattr(target, "getvalue")
               else fig.axes[0].get_title() or "(bytes)", dpi)

    def spy_tight(fig, dpi):  # write_png's one-draw PNG (savefig where it declines)
        png = tight_png(fig, dpi)
        if png is not None:
            record(fig, fig.axes[0].get_title() or "(drawn once)", dpi)
        return png

    monkeypatch.setattr(Figure, "savefig", spy)
    monkeypatch.setattr(pneumact.plotting, "_tight_png", spy_tight)
    return seen


def assert_scaled(drawn, folder) -> None:
    assert drawn, "no figure was written"
    for name, width, panels in drawn:
        assert width <= ref.MAX_FIGURE_WIDTH_PX, f"{name}: {width:.0f} px wide"
        assert min(panels) >= ref.MIN_PANEL_WIDTH_PX, f"{name}: a panel {min(panels):.0f} px"
    for png in folder.glob("*.png"):
        assert png_size(png)[0] <= ref.MAX_FIGURE_WIDTH_PX, png.name


def png_size(path) -> tuple[int, int]:
    with Image.open(path) as image:
        return image.size


@pytest.fixture(scope="module")
def campaign(vgt):
    """Twelve short records, like `pneumact campaign` writes (sweep, ramps, presliding)."""
    speeds = tuple(np.geomspace(5e-3, 4e-2, ref.MANY_RECORDS - 2))
    records = synthetic_campaign(vgt, paper_campaign(vgt, speeds=speeds, sweep_period=4.0),
                                 seed=2)
    assert len(records) == ref.MANY_RECORDS
    return records


def test_validate_draws_twelve_records_as_a_grid(campaign, drawn, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for record in campaign:
        record.save(tmp_path / "bench" / f"{record.source}.csv")
    result = runner.invoke(app, ["validate", "bench", "--out", "val"])
    assert result.exit_code == 0, result.output
    assert {p.name for p in (tmp_path / "val").glob("*.png")} == {
        "loops.png", "time.png", "residuals.png"}
    assert_scaled(drawn, tmp_path / "val")


def test_records_beyond_a_page_make_a_figure_per_page(campaign, drawn, tmp_path,
                                                      monkeypatch):
    """Beyond a page of records the figure grew taller; now each page is a figure of its
    own (loops.png, loops-2.png, ...) and the report shows every page. Pages of 5 here,
    so that the campaign's 12 records make three."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(plotting, "PANELS_PER_PAGE", 5)
    for record in campaign:
        record.save(tmp_path / "bench" / f"{record.source}.csv")
    result = runner.invoke(app, ["validate", "bench", "--out", "val"])
    assert result.exit_code == 0, result.output
    pages = {f"{name}{suffix}.png" for name in ("loops", "time", "residuals")
             for suffix in ("", "-2", "-3")}
    assert {p.name for p in (tmp_path / "val").glob("*.png")} == pages
    assert_scaled(drawn, tmp_path / "val")
    one_row = png_size(tmp_path / "val" / "loops-3.png")[1]  # 2 records: one row
    assert png_size(tmp_path / "val" / "loops.png")[1] < 2.5 * one_row  # 5 records: two
    html = (tmp_path / "val" / "report.html").read_text(encoding="utf-8")
    assert html.count("<img") == len(pages) and "(page 3 of 3)" in html


def test_a_fit_beyond_a_page_of_records_writes_a_figure_per_page(vgt, tmp_path,
                                                                 monkeypatch):
    """fit.png (and identify paper's joint_fit.png, drawn by the same plot_fit) per page
    of records; pages of 2 here, so that three records make two."""
    import pneumact as pa

    monkeypatch.setattr(plotting, "PANELS_PER_PAGE", 2)
    model = pa.Actuator(vgt, valve=pa.PressureSource())
    run = pa.simulate(model, pa.PressureCycle(high=100e3, low=40e3, period=2.0,
                                              n_points=201))
    rng = np.random.default_rng(0)
    records = [pa.Record.from_arrays(
        run.time, {"pressure": run["pressure"] + rng.normal(0.0, 20.0, run.time.size),
                   "position": run["position"] + rng.normal(0.0, 1e-6, run.time.size)},
        source=f"{kind}.csv") for kind in ("sweep", "ramp", "presliding")]
    result = pa.fit(model, records, ["Fc"], optimizer=pa.Optimizer(max_nfev=2))
    assert result.fit_pages == 2
    result.write(tmp_path / "fit")
    assert {p.name for p in (tmp_path / "fit").glob("fit*.png")} == {"fit.png", "fit-2.png"}
    # two records side by side, then the third alone
    assert png_size(tmp_path / "fit" / "fit-2.png")[0] < 0.7 * png_size(
        tmp_path / "fit" / "fit.png")[0]
    html = (tmp_path / "fit" / "report.html").read_text(encoding="utf-8")
    assert "(page 2 of 2)" in html


def test_measured_and_model_of_twelve_records_wraps_into_rows(tmp_path):
    """The figure of a joint fit (`identify paper`'s joint_fit.png, `fit`'s fit.png)."""
    time = np.linspace(0.0, 1.0, 50)
    entries = [(f"record {i}", time, {"position": time}, {"position": 0.9 * time},
                {"position": "m"}) for i in range(ref.MANY_RECORDS)]
    fig = plotting.plot_measured_and_model(entries, ["position"])
    columns = {round(ax.get_position().x0, 3) for ax in fig.axes if ax.get_visible()}
    assert len(columns) == plotting.MAX_PANEL_COLUMNS
    path = plotting.save_figure(fig, tmp_path / "joint_fit.png")
    width = png_size(path)[0]
    assert width <= ref.MAX_FIGURE_WIDTH_PX
    panel = min(ax.get_window_extent().width for ax in fig.axes) * plotting.PNG_DPI / fig.dpi
    assert panel >= ref.MIN_PANEL_WIDTH_PX


def test_a_log_axis_within_a_decade_is_labelled_with_numbers():
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0.3, 3.0], [0.0, 1.0])
    ax.set_xscale("log")
    plotting.label_log_axis(ax)
    fig.canvas.draw()
    labels = [t.get_text() for t in ax.get_xticklabels() if t.get_text()]
    low, high = ax.get_xlim()
    shown = [float(x) for x in labels if low <= float(x) <= high]
    assert len(shown) >= 3, labels
    plt.close(fig)


def test_validate_prints_and_reports_mm_um_and_kpa_and_writes_si(campaign, tmp_path,
                                                                 monkeypatch):
    """Units a person reads (issue #42): µm residuals, kPa·mm loop areas; CSV stays SI."""
    monkeypatch.chdir(tmp_path)
    for record in (campaign[0], campaign[-1]):  # the sweep and the presliding test
        record.save(tmp_path / "bench" / f"{record.source}.csv")
    result = runner.invoke(app, ["validate", "bench", "--out", "val"])
    assert result.exit_code == 0, result.output
    assert "rms [µm]" in result.output and "e-06" not in result.output
    html = (tmp_path / "val" / "report.html").read_text(encoding="utf-8")
    assert "rms [µm]" in html and "kPa·mm" in html and "Pa*m" not in html


    metrics = pd.read_csv(tmp_path / "val" / "metrics.csv")
    assert metrics["rms"].max() < 1e-3  # metres


def test_control_step_prints_its_errors_in_um_or_mm(tmp_path):
    """The loop of test_cli_control.py's step test (its kernel serves both)."""
    result = runner.invoke(app, ["control", "step", "--plant", "command", "--start", "4",
                                 "--stop", "8", "--t-end", "0.6", "--sample-time", "1e-3",
                                 "--out", str(tmp_path / "step")])
    assert result.exit_code == 0, result.output
    rows = {line.split("│")[1].strip(): line.split("│")[3].strip()
            for line in result.output.splitlines() if line.count("│") == 4}
    assert rows["steady_state_error"] in ("µm", "mm") and rows["start"] == "mm"
    assert rows["iae"] in ("µm·s", "mm·s")
    html = (tmp_path / "step" / "report.html").read_text(encoding="utf-8")
    table = next(t for t in pd.read_html(io.StringIO(html)) if "metric" in t.columns)
    units = dict(zip(table["metric"], table["unit"], strict=True))
    assert units["steady_state_error"] in ("µm", "mm") and units["start"] == "mm"
    metrics = pd.read_csv(tmp_path / "step" / "metrics.csv")
    assert dict(zip(metrics["metric"], metrics["unit"], strict=True))["start"] == "m"


def test_validate_does_not_compare_a_record_with_its_own_input(vgt, campaign):
    """A pressure-driven record: its pressure drives the model; comparing it would give
    a fit of 100 % that says nothing (issue #42)."""
    import pneumact as pa
    from pneumact.errors import DataError
    from pneumact.validation import validate

    presliding = campaign[-1]
    model = pa.Actuator(vgt, valve=pa.PressureRegulator())
    validation = validate(model, presliding, signals=("position", "pressure"))
    assert validation.records[0].input == "pressure"
    assert set(validation.metrics()["signal"]) == {"position"}
    assert "pressure not compared" in validation.verdicts()["reasons"].iloc[0]
    with pytest.raises(DataError, match="repeat its input"):
        validate(model, presliding, signals=("pressure",))


def test_a_mistyped_command_and_flags_in_help():
    result = runner.invoke(app, ["batch"])
    assert result.exit_code != 0 and "simulate-batch" in result.output
    result = runner.invoke(app, ["campaign", "--help"])
    assert result.exit_code == 0 and "--plan" in result.output
    assert "<bool>" not in result.output


def test_sliding_motion_tells_stick_slip_from_steady_sliding():
    from pneumact.analysis import sliding_motion

    t = np.linspace(0.0, 1.0, 2001)
    steady = sliding_motion(1e-2 * t, np.full_like(t, 1e-2))
    assert not steady.stick_slip and steady.min_speed == pytest.approx(1e-2)
    jumps = 1e-3 * (np.sin(2 * np.pi * 20 * t) ** 2)  # stops 40 times
    stepping = sliding_motion(1e-2 * t, 1e-2 * jumps / jumps.max() * 2)
    assert stepping.stick_slip and stepping.stops >= 20


def test_simulate_says_the_default_run_sticks_and_slips(tmp_path):
    result = runner.invoke(app, ["simulate", "--out", str(tmp_path / "sim")])
    assert result.exit_code == 0, result.output
    assert "stick-slip" in result.output and "speed range" in result.output


def test_control_profile_takes_a_measured_profile_with_noise_at_the_rest_stop(tmp_path):
    """A bench record rests at 0 with its sensor's noise, a few µm below 0 (issue #42);
    a profile a millimetre outside the stroke is still refused."""
    rng = np.random.default_rng(1)
    time = np.linspace(0.0, 1.2, 121)
    position = np.interp(time, [0.0, 0.3, 0.8, 1.2], [0.0, 0.0, 5.0, 5.0])
    position = position + rng.normal(0.0, 1e-3, time.size)  # 1 µm of noise [mm]
    assert position.min() < -0.002
    profile = tmp_path / "profile.csv"
    np.savetxt(profile, np.column_stack([time, position]), delimiter=",",
               header="time [s],position [mm]", comments="")
    args = ["control", "profile", str(profile), "--plant", "command", "--sample-time",
            "1e-3"]  # the loop of test_cli_control.py's profile test: its kernel
    result = runner.invoke(app, [*args, "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert "past an end of the stroke" in result.output
    np.savetxt(profile, np.column_stack([time, position - 1.0]), delimiter=",",
               header="time [s],position [mm]", comments="")
    result = runner.invoke(app, [*args, "--out", str(tmp_path / "bad")])
    assert result.exit_code == 2 and "lowest set-point" in result.output


def test_a_record_has_one_name_in_every_table(vgt, campaign, tmp_path):
    """`bench/presliding.csv` is `presliding.csv` in validation and fit tables alike, never
    its folder's path (issue #42)."""
    import pneumact as pa
    from pneumact.identification import fit
    from pneumact.validation import validate

    campaign[-1].save(tmp_path / "bench" / "presliding.csv")
    record = pa.read_record(tmp_path / "bench" / "presliding.csv")
    record = record.crop(0.0, 0.8)
    model = pa.Actuator(vgt, valve=pa.PressureSource())
    names = set(validate(model, record).metrics()["record"]) - {"all records"}
    result = fit(model, record, ["F0"])
    assert names == set(result.to_pandas("statistics")["record"]) == {
        os.path.basename(record.source)}
    assert next(iter(names)).startswith("presliding.csv")  # (cropped: "... (0..0.8 s)")


def test_the_campaign_plan_fits_80_columns_with_units_in_its_headers(tmp_path):
    result = runner.invoke(app, ["campaign", "--plan", "--out", str(tmp_path / "plan")],
                           terminal_width=80)
    assert result.exit_code == 0, result.output
    assert "…" not in result.output and "[kPa]" in result.output and "[mm/s]" in result.output
    assert all(len(line) <= 80 for line in result.output.splitlines() if "│" in line
               or "─" in line)
    plan = pd.read_csv(tmp_path / "plan" / "plan.csv")
    for test in plan["test"]:
        assert f" {test} " in result.output


def test_control_tune_exits_non_zero_when_its_gains_miss_the_spec(tmp_path):
    """The rig of test_tuning.py's command-line test, a spec it cannot meet: the files
    are written, the feasibility line says so, and the exit code tells a script."""
    rig = ["--plant", "rig", "--params", "canudas1995"]
    result = runner.invoke(app, ["control", "tune", *rig, "--kp", "3", "--ki", "4",
                                 "--spec", "settling=0.05,overshoot=0%,no-hunting",
                                 "--n-global", "2", "--max-evaluations", "2", "--at", "0",
                                 "--out", str(tmp_path / "tune")])
    assert result.exit_code == 3, result.output
    assert "Does NOT meet the specs" in result.output
    assert (tmp_path / "tune" / "gains.toml").is_file()


def test_a_batch_of_many_varied_parameters_wraps_its_panels():
    """Eight varied inputs, two features: 16 panels, at most 4 side by side."""
    import matplotlib.pyplot as plt

    from pneumact.simulation.batch import BatchResult

    rng = np.random.default_rng(0)
    names = [f"p{i}" for i in range(8)]
    table = pd.DataFrame({**{n: rng.uniform(1.0, 2.0, 5) for n in names},
                          "loop_width_pressure": rng.uniform(1e3, 2e3, 5),
                          "stroke": rng.uniform(0.01, 0.02, 5),
                          "status": ["ok"] * 5, "error": [""] * 5})
    fig = BatchResult(table, units=dict.fromkeys(names, "1")).plot()
    fig.canvas.draw()
    scale = plotting.PNG_DPI / fig.dpi
    assert fig.get_figwidth() * plotting.PNG_DPI <= ref.MAX_FIGURE_WIDTH_PX
    widths = [ax.get_window_extent().width * scale for ax in fig.axes if ax.get_visible()]
    assert len(widths) == 16 and min(widths) >= ref.MIN_PANEL_WIDTH_PX
    plt.close(fig)


def test_sensitivity_oat_writes_its_loops_with_zooms(tmp_path, drawn, monkeypatch):
    """At full scale the loops of ±variations lie on one another: loops.png shows each
    parameter's whole loop, its break-away and its reversal (issue #42)."""
    from matplotlib.figure import Figure

    import pneumact.plotting

    titles: list[str] = []
    # the spies of ``drawn``: keep them, note the panel titles
    savefig, tight_png = Figure.savefig, pneumact.plotting._tight_png

    def with_titles(fig, target, *args, **kw):
        titles.extend(ax.get_title() for ax in fig.axes)
        return savefig(fig, target, *args, **kw)

    def tight_with_titles(fig, dpi):
        titles.extend(ax.get_title() for ax in fig.axes)
        return tight_png(fig, dpi)

    monkeypatch.setattr(Figure, "savefig", with_titles)
    monkeypatch.setattr(pneumact.plotting, "_tight_png", tight_with_titles)
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["sensitivity", "oat", "--out", "oat"])
    assert result.exit_code == 0, result.output
    assert any("at break-away" in t for t in titles) and any("whole loop" in t
                                                              for t in titles)
    assert_scaled(drawn, tmp_path / "oat")


class _SweepRecord:
    """What plot_band reads of a record: its source, kind, time and signals [SI]."""

    def __init__(self, time: np.ndarray, signals: dict[str, np.ndarray]) -> None:
        self.source, self.meta, self.time, self._signals = "bench/sweep.csv", {
            "kind": "sweep"}, time, signals

    def __getitem__(self, name: str) -> np.ndarray:
        return self._signals[name]


def test_band_png_is_readable_with_units_and_a_micrometre_zoom(tmp_path):
    """band.png of `identify paper`: its size, the axes' units, and the zoom in µm where
    a band of some µm on a stroke of mm shows (issue #42: the band was invisible)."""
    from types import SimpleNamespace

    from pneumact.identification.paper import PaperIdentification

    time = np.linspace(0.0, 4.0, 400)
    pressure = 1.5e5 + 1e5 * np.sin(np.pi * time / 4.0) ** 2
    position = 0.01 * np.sin(np.pi * time / 4.0) ** 2  # a 10 mm stroke
    spread = 5e-6 * np.ones_like(time)  # a band of ±5 µm
    record = _SweepRecord(time, {"pressure": pressure, "position": position + 1e-6})
    nominal = {"pressure": pressure, "position": position}
    band = SimpleNamespace(
        time=time, level=0.95, nominal=nominal,
        lower={"position": position - spread}, upper={"position": position + spread},
        samples={"pressure": [pressure] * 3,
                 "position": [position + d * spread for d in (-1, 0, 1)]})
    result = SimpleNamespace(records=[record], band=lambda chosen: band)
    fig = PaperIdentification.plot_band(result)  # type: ignore[arg-type]
    labels = [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]
    assert labels == [("chamber pressure [kPa abs]", "position [mm]"),
                      ("time [s]", "position [mm]"),
                      ("time [s]", "position − identified model [µm]")]
    low, high = fig.axes[2].get_ylim()  # the zoom shows the ±5 µm band, in µm
    assert 5.0 <= high < 50.0 and -50.0 < low <= -5.0, (low, high)
    path = plotting.save_figure(fig, tmp_path / "band.png")
    assert png_size(path)[0] <= ref.MAX_FIGURE_WIDTH_PX
    panel = min(ax.get_window_extent().width for ax in fig.axes) * plotting.PNG_DPI / fig.dpi
    assert panel >= ref.MIN_PANEL_WIDTH_PX


def _friction_records(n: int):
    """``n`` short friction records (a sine of position, a smooth Coulomb force)."""
    import pneumact as pa

    time = np.linspace(0.0, 1.0, 101)
    return [pa.Record.from_arrays(time, {"position": 1e-3 * np.sin(2 * np.pi * time),
                                         "friction": 5.0 * np.tanh(np.cos(2 * np.pi * time)
                                                                   * 50) + 0.1 * k},
                                  source=f"seal_{k}.csv") for k in range(n)]


def test_a_comparison_and_a_friction_validation_page_their_records(drawn, tmp_path,
                                                                    monkeypatch):
    """The two record figures left growing taller beyond a page (issue 42, item 5):
    compare's held-out loops and a friction validation's force figure, a figure per
    page of records (pages of 2 here: five records make three)."""
    from types import SimpleNamespace

    from pneumact.validation.compare import FrictionComparison, LawScore
    from pneumact.validation.friction import FrictionValidation

    monkeypatch.setattr(plotting, "PANELS_PER_PAGE", 2)
    records = _friction_records(5)
    score = LawScore("LuGre", None, predictions=records, residuals=[np.zeros(3)])
    comparison = FrictionComparison(model=SimpleNamespace(input_signal="position"),
                                    scores=[score], train=[], test=records,
                                    held_out=list(range(5)), signals=("friction",))
    assert list(comparison.figures()) == ["loops", "loops-2", "loops-3"]
    assert len(comparison.figures()["loops-3"]().axes) == 1  # the fifth record alone
    frames = {r.source: pd.DataFrame({"time": r.time, "velocity": np.gradient(
        r["position"], r.time), "measured": r["friction"], "predicted": r["friction"]})
        for r in records}
    validation = FrictionValidation("LuGre", ["seal_0.csv"], frames, pd.DataFrame())
    validation.write(tmp_path / "seal")
    assert {p.name for p in (tmp_path / "seal").glob("*.png")} == {
        "force.png", "force-2.png", "force-3.png"}
    assert_scaled(drawn, tmp_path / "seal")
    html = (tmp_path / "seal" / "report.html").read_text(encoding="utf-8")
    assert "(page 3 of 3)" in html
