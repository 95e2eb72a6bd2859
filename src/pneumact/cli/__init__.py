"""The ``pneumact`` command line: a thin layer over the public API.

    pneumact simulate                         # vgt-paper, slow pressure cycle -> pneumact-out/
    pneumact simulate --valve command --t-end 10 --out run1
    pneumact friction-test stick-slip --t-end 5
    pneumact simulate-batch table.csv --out batch1
    pneumact params list | show NAME|FILE | check FILE
    pneumact campaign --out bench                # synthetic bench records (CSV)
    pneumact identify paper bench --out ident    # the paper's staged procedure
    pneumact identify friction DATA_EMPS.mat --validate DATA_EMPS_PULSES.mat
    pneumact fit bench/presliding.csv --free sigma0,sigma1 --offsets position
    pneumact validate bench/sweep.csv --out val   # model against records, HTML report
    pneumact compare bench/*.csv --laws lugre,gms:4,dahl   # which friction law fits?
    pneumact reproduce                           # the whole paper, one folder
    pneumact control step --start 4 --stop 8     # closed-loop position step, metrics
    pneumact control hunting                     # Canudas et al. (1995) hunting
    pneumact export fmu --out actuator.fmu       # FMI 2.0 Model Exchange FMU

Options map onto exactly the objects of the library (parameter set, friction model,
valve, experiment, solver); no physics lives here. Output files are written only after
a successful run, atomically, and together. A user's mistake prints one red line
``error: ...`` on stderr and exits with code 2.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Any, cast

import typer
from typer.core import TyperGroup, TyperOption

from pneumact.cli.common import err_console, out_console, print_error, show_estimates
from pneumact.cli.compare import compare_command
from pneumact.cli.control import control_app
from pneumact.cli.export import export_app
from pneumact.cli.friction_test import friction_test_app
from pneumact.cli.identify import campaign, fit_command, identify_app
from pneumact.cli.params import params_app
from pneumact.cli.reproduce import reproduce_command
from pneumact.cli.sensitivity import sensitivity
from pneumact.cli.simulate import simulate
from pneumact.cli.simulate_batch import simulate_batch
from pneumact.cli.validate import validate_command
from pneumact.version import __version__


class _Commands(TyperGroup):
    """The command group: a mistyped command is answered with the commands whose name
    holds it as a word too (``batch`` -> ``simulate-batch``), beside typer's close
    matches."""

    def resolve_command(self, ctx, args):
        try:
            return super().resolve_command(ctx, args)
        except Exception as error:  # typer's own click's UsageError (not click's)
            typo = args[0] if args else ""
            words = [name for name in self.commands
                     if typo and typo != name and typo in name.split("-")]
            message = getattr(error, "message", None)
            if words and isinstance(message, str) and "Did you mean" not in message:
                error.message = (  # type: ignore[attr-defined]
                    f"{message.rstrip('.')}. Did you mean "
                    f"{', '.join(repr(name) for name in words)}?")
            raise


def _flags_show_no_type(show_type):
    """A flag takes no value: typer's help shows bool flags as ``<bool>``; show none."""

    def display_type_rich(self, ctx):
        return None if getattr(self, "is_flag", False) else show_type(self, ctx)

    return display_type_rich


TyperOption.display_type_rich = _flags_show_no_type(  # type: ignore[method-assign]
    TyperOption.display_type_rich)


class OneErrorPrefix(_Commands):
    """The root command: the parser's usage errors (a mistyped option or value) end in
    one ``error:`` line, as every command's own refusals do, instead of a box titled
    "Error"; everything else as typer does it."""

    def main(self, args: Sequence[str] | None = None, prog_name: str | None = None,
             complete_var: str | None = None, standalone_mode: bool = True,
             windows_expand_args: bool = True, **extra: Any) -> Any:
        import sys

        # click's exception base as typer uses it (typer may vendor its own click)
        click_exception = cast("type[Exception]", next(
            c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException"))
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode,
                                windows_expand_args, **extra)
        try:
            code = super().main(args, prog_name, complete_var, False, windows_expand_args,
                                **extra)
        except click_exception as exc:
            exit_code = int(getattr(exc, "exit_code", 2))
            if type(exc).__name__ == "NoArgsIsHelpError":  # the help is already shown
                sys.exit(exit_code)
            context = getattr(exc, "ctx", None)
            if context is not None:
                err_console.print(context.get_usage(), markup=False, highlight=False)
                err_console.print(f"Try '{context.command_path} --help' for help.",
                                  markup=False, highlight=False)
            print_error(getattr(exc, "format_message", exc.__str__)())
            sys.exit(exit_code)
        except typer.Abort:
            print_error("aborted")
            sys.exit(1)
        sys.exit(code if isinstance(code, int) else 0)


app = typer.Typer(
    cls=OneErrorPrefix,
    name="pneumact",
    help="Pneumatic diaphragm actuators with LuGre friction: simulate, test, inspect.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


#: said before the first compilation the disk cache cannot spare (a cold start)
COMPILING = ("compiling the model (once on this machine; later runs load it at once)")


def _version(value: bool) -> None:
    if value:
        out_console.print(f"pneumact {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    version: Annotated[bool, typer.Option("--version", callback=_version, is_eager=True,
                                          help="Print the version and exit.")] = False,
    engine: Annotated[str | None, typer.Option(
        "--engine", help="Where the model's equations run: 'c' (built once per model with "
        "the C compiler, seconds), 'numba' (compiled once per model, about a minute) or "
        "'auto' (C where a compiler is found, else numba). Default: $PNEUMACT_ENGINE, "
        "else auto.")] = None,
) -> None:
    """Pneumatic diaphragm actuators with LuGre friction."""
    import os

    from pneumact.core.c_engine import ENGINE_VARIABLE, ENGINES
    from pneumact.core.compile_lock import on_first_compile

    if engine is not None:
        if engine not in ENGINES:
            raise typer.BadParameter(f"{engine!r} is not one of {', '.join(ENGINES)}",
                                     param_hint="--engine")
        os.environ[ENGINE_VARIABLE] = engine  # this process, its threads and its workers
    show_estimates()
    on_first_compile(lambda: err_console.print(COMPILING, style="yellow"))


app.command()(simulate)
app.command("simulate-batch")(simulate_batch)
app.add_typer(friction_test_app, name="friction-test")
app.add_typer(params_app, name="params")
app.command("campaign")(campaign)
app.add_typer(identify_app, name="identify")
app.command("fit")(fit_command)
app.command("compare")(compare_command)
app.command("sensitivity")(sensitivity)
app.command("validate")(validate_command)
app.command("reproduce")(reproduce_command)
app.add_typer(control_app, name="control")
app.add_typer(export_app, name="export")


def finite_float(text: str) -> float:
    """A number option's value: NaN and infinities are never a setting."""
    import math

    try:
        value = float(text)
    except ValueError:
        raise typer.BadParameter(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise typer.BadParameter(f"{text} is not a finite number")
    return value


def escape_help_markup(typer_app: typer.Typer, done: set[int] | None = None) -> None:
    """Rich reads '[kPa]' in a help text as markup and drops it: escape every option's
    and command's help once, so that the units show in --help; and make every number
    option refuse NaN and infinities."""
    import inspect
    import typing

    from rich.markup import escape

    done = set() if done is None else done
    for info in typer_app.registered_commands:
        if info.help and id(info) not in done:
            info.help = escape(info.help)
        done.add(id(info))
        callback = info.callback
        if callback is None:
            continue
        if callback.__doc__ and id(callback) not in done:
            callback.__doc__ = escape(inspect.cleandoc(callback.__doc__))
            done.add(id(callback))
        # typer evaluates string annotations anew (new option objects) each time it
        # builds the command: keep the evaluated ones, whose help is escaped here
        annotations = inspect.get_annotations(callback, eval_str=True)
        callback.__annotations__ = annotations
        for annotation in annotations.values():
            if typing.get_origin(annotation) is not typing.Annotated:
                continue
            base, *options = typing.get_args(annotation)
            for option in options:
                if id(option) in done:
                    continue
                done.add(id(option))
                if getattr(option, "help", None):
                    option.help = escape(option.help)
                if base in (float, float | None) and hasattr(option, "parser") and \
                        option.parser is None and getattr(option, "click_type", None) is None:
                    option.parser = finite_float
    for group in typer_app.registered_groups:
        if group.typer_instance is not None:
            escape_help_markup(group.typer_instance, done)


escape_help_markup(app)

__all__ = ["app"]
