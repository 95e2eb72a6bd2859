"""``pneumact params list | show | check``: the parameter sets and their values."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.table import Table
from rich.text import Text

from pneumact.cli.common import EXIT_CHECK_FAILED, err_console, out_console, user_errors

params_app = typer.Typer(help="List, show and check parameter sets.", no_args_is_help=True)


@params_app.command("list")
def params_list() -> None:
    """List the parameter sets shipped with pneumact."""
    with user_errors():
        from pneumact.parameters import available_params

        table = Table(title="shipped parameter sets")
        table.add_column("name", style="bold")
        table.add_column("description")
        for name, description in available_params():
            table.add_row(name, description)
        out_console.print(table)


@params_app.command("show")
def params_show(
    name: Annotated[str, typer.Argument(help="A shipped set name or a .toml file.")],
) -> None:
    """Show every parameter: value as given, in SI, source and meaning."""
    with user_errors():
        from pneumact.parameters import load_params

        parameter_set = load_params(name)
        frame = parameter_set.to_pandas()
        table = Table(title=f"{parameter_set.name}: {parameter_set.description}")
        for column in ("name", "given", "SI value", "source", "description"):
            table.add_column(column, overflow="fold")
        for row in frame.itertuples(index=False):
            si = f"{row.value:.6g} {row.unit}".rstrip()
            table.add_row(row.name, row.given or "", si, row.source, row.description)
        out_console.print(table)
        _print_passivity(parameter_set)


@params_app.command("check")
def params_check(
    file: Annotated[str, typer.Argument(help="A .toml parameter file (or a shipped name).")],
) -> None:
    """Load and validate a parameter file: prints OK (with warnings about values that are
    legal but odd, and about LuGre passivity) or the error (exit code 2)."""
    with user_errors(code=EXIT_CHECK_FAILED):
        from pneumact.parameters import load_params

        parameter_set = load_params(file)
        out_console.print(Text(f"OK: {parameter_set.name} ({len(parameter_set)} parameters "
                               "given)", style="green"))
        _print_passivity(parameter_set)


def _print_passivity(parameter_set) -> None:
    """The set's passivity warning, always (the other commands leave it to here)."""
    from pneumact.parameters.validation import passivity_note

    note = passivity_note(parameter_set.values, parameter_set.name)
    if note:
        err_console.print(Text(f"warning: PassivityWarning: {note}", style="yellow"),
                          soft_wrap=True)
