"""``pneumact friction-test KIND``: the classic friction experiments on the friction rig.

One subcommand per experiment of ``pneumact.experiments.friction``, with one option per
setting of its settings object, generated from the object's fields: whatever the Python
API can set, the command line can too.
"""

from __future__ import annotations

import inspect
import typing
from collections.abc import Callable
from dataclasses import MISSING, fields
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from pneumact.checks import check_out_dir
from pneumact.cli.common import (
    ElementsOption,
    Friction,
    FrictionOption,
    ModelOptions,
    ParamsOption,
    fmt,
    friction_of,
    out_console,
    use_agg,
    user_errors,
    write_outputs,
)
from pneumact.errors import ExperimentError
from pneumact.experiments.friction import FRICTION_TESTS, FrictionTest

friction_test_app = typer.Typer(help="Run a classic friction experiment (Canudas de Wit et "
                                     "al. 1995) on the friction rig; write CSV and PNG.",
                                no_args_is_help=True)


#: settings whose option has another name than the setting (none: the names are the API's)
OPTION_NAMES: dict[str, str] = {}
#: old option names still accepted (hidden from --help), by the setting they set
DEPRECATED = {"t_end": "--duration"}


def option_name(field_name: str) -> str:
    return OPTION_NAMES.get(field_name, "--" + field_name.replace("_", "-"))


def _is_sequence(annotation) -> bool:
    return typing.get_origin(annotation) is tuple or "tuple" in str(annotation)


def _parameter(field, annotation) -> inspect.Parameter:
    """The typer option of one setting: numbers as they are, sequences comma-separated."""
    help_text = field.metadata.get("help", "")
    if _is_sequence(annotation):
        shown = ",".join(f"{v:g}" for v in field.default)
        kind: Any = Annotated[str | None, typer.Option(
            option_name(field.name), help=f"{help_text}; comma-separated [default: {shown}]",
            show_default=False)]
        return inspect.Parameter(field.name, inspect.Parameter.KEYWORD_ONLY, default=None,
                                 annotation=kind)
    optional = type(None) in typing.get_args(annotation)
    base = float if "float" in str(annotation) else int
    kind = Annotated[base | None if optional else base,
                     typer.Option(option_name(field.name), help=help_text)]
    default = None if field.default is MISSING else field.default
    return inspect.Parameter(field.name, inspect.Parameter.KEYWORD_ONLY, default=default,
                             annotation=kind)


def _settings(cls: type[FrictionTest], given: dict[str, Any]) -> dict[str, Any]:
    hints = typing.get_type_hints(cls)
    settings = {}
    for f in fields(cls):
        value = given[f.name]
        if _is_sequence(hints[f.name]):
            if value is None:
                continue
            try:
                value = tuple(float(v) for v in value.split(",") if v.strip())
            except ValueError:
                raise ExperimentError(f"{option_name(f.name)} = {value!r}: give numbers "
                                      "separated by commas, e.g. 0.1,1,10") from None
        settings[f.name] = value
    return settings


def _command(cls: type[FrictionTest]):
    hints = typing.get_type_hints(cls)
    common = [
        inspect.Parameter("params", inspect.Parameter.KEYWORD_ONLY, default="canudas1995",
                          annotation=ParamsOption),
        inspect.Parameter("friction", inspect.Parameter.KEYWORD_ONLY, default=Friction.lugre,
                          annotation=FrictionOption),
        inspect.Parameter("elements", inspect.Parameter.KEYWORD_ONLY, default=None,
                          annotation=ElementsOption),
        inspect.Parameter("out", inspect.Parameter.KEYWORD_ONLY, default=Path("pneumact-out"),
                          annotation=Annotated[Path, typer.Option(
                              help="Output directory (friction_test.csv, "
                                   "friction_test_curve.csv, friction_test.png).")]),
    ]
    settings = [_parameter(f, hints[f.name]) for f in fields(cls)]
    aliases = [inspect.Parameter(f"{f.name}_deprecated", inspect.Parameter.KEYWORD_ONLY,
                                 default=None, annotation=Annotated[float | None, typer.Option(
                                     DEPRECATED[f.name], hidden=True,
                                     help=f"Old name of {option_name(f.name)}.")])
               for f in fields(cls) if f.name in DEPRECATED]

    def command(**given) -> None:
        params, friction, out = given.pop("params"), given.pop("friction"), given.pop("out")
        elements = given.pop("elements")
        with user_errors():
            _take_deprecated(cls, given)
            out = check_out_dir("--out", out)
            test = cls(**_settings(cls, given))
            law = friction_of(ModelOptions(friction=friction, elements=elements))
            _run(test, params, law, out)

    # typer reads the parameters from the signature built here (mypy knows no such attribute)
    command.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
        [*common, *settings, *aliases])
    command.__annotations__ = {p.name: p.annotation for p in (*common, *settings, *aliases)}
    command.__doc__ = f"{cls.help[0].upper()}{cls.help[1:]}."
    command.__name__ = cls.kind.replace("-", "_")
    return command


def _take_deprecated(cls: type[FrictionTest], given: dict[str, Any]) -> None:
    """An old option name (``--duration``) sets its setting, with a warning; given with the
    new name too, it is refused."""
    import warnings

    defaults = {f.name: f.default for f in fields(cls)}
    for name, old in DEPRECATED.items():
        value = given.pop(f"{name}_deprecated", None)
        if value is None or name not in given:
            continue
        if given[name] != defaults[name]:
            raise ExperimentError(f"{old} is the old name of {option_name(name)}; give only "
                                  f"{option_name(name)}")
        warnings.warn(f"{old} is deprecated: use {option_name(name)}", FutureWarning,
                      stacklevel=2)
        given[name] = value


def _run(test: FrictionTest, params_name: str, model, out: Path) -> None:
    from pneumact.analysis.friction_tests import run_friction_test
    from pneumact.cli.common import COMPILING, err_console, load_quietly
    use_agg()
    import matplotlib.pyplot as plt

    from pneumact.plotting import plot_friction_test, save_figure

    params = load_quietly(params_name)
    with err_console.status(f"running the {test.kind} test ({COMPILING})"):
        result = run_friction_test(test, params, friction=model)
    fig = plot_friction_test(result, test.kind)
    writers: dict[str, Callable[[Path], object]] = {"friction_test.csv": result.result.save}
    curve = result.table
    if curve is not None:
        writers["friction_test_curve.csv"] = lambda path: save_derived_table(curve, path)
    writers["friction_test.png"] = lambda path: save_figure(fig, path)
    try:
        written = write_outputs(out, writers)
    finally:
        plt.close(fig)
    run = result.result
    table = Table(title=f"pneumact friction-test {test.kind}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("friction model", model.name)
    table.add_row("drive", result.drive_quantity)
    table.add_row("runs", str(max(1, len(result.runs))))
    table.add_row("duration [s]", fmt(float(run.time[-1] - run.time[0])))
    table.add_row("samples", str(len(run.time)))
    table.add_row("solver steps", str(run.meta.get("steps", "n/a")))
    table.add_row("wall time [s]", fmt(run.meta.get("wall_time_s", float("nan")), 3))
    out_console.print(table)
    for path in written:
        out_console.print(f"wrote {path}")


def save_derived_table(frame, path: Path) -> None:
    """Write a derived table whose columns are named ``name [unit]`` (SI)."""
    from pneumact.io.tables import parse_cell, write_table

    names, units = [], {}
    for column in map(str, frame.columns):
        name, unit = parse_cell(column)
        names.append(name)
        if unit:
            units[name] = unit
    renamed = frame.set_axis(names, axis=1)
    renamed.attrs = {}
    write_table(renamed, path, units)


for _kind, _cls in FRICTION_TESTS.items():
    friction_test_app.command(_kind)(_command(_cls))
