"""``pneumact reproduce [--quick] [--out DIR]``: the whole seed paper, one folder."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.text import Text

from pneumact.checks import check_out_dir, check_seed
from pneumact.cli.common import (
    ParamsOption,
    out_console,
    progress_display,
    the_call,
    user_errors,
)


def reproduce_command(
    ctx: typer.Context,
    params: ParamsOption = "vgt-paper",
    quick: Annotated[bool, typer.Option("--quick", help="Small campaign and samples (for "
                                                        "tests); rough numbers.")] = False,
    seed: Annotated[int, typer.Option(help="Seed of the synthetic noise and samples "
                                             "(>= 0).")] = 0,
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-paper"),
    seal_data: Annotated[Path | None, typer.Option(
        "--seal-data", help="Folder of the TU Delft cylinder's seal records "
                            "(O-ring_<p>bar.csv) for the section on real friction data.")
    ] = None,
) -> None:
    """Reproduce the paper: Table I, Figs. 2, 3, 5 and 6, the identification on a
    synthetic campaign and on campaigns made by richer models, the sensitivity across
    operating conditions, every statement of the paper with the conditions in which it
    holds, and (--seal-data) friction measured on a real seal; writes OUT/index.html with every
    table and figure (also as CSV and PNG)."""
    with user_errors():
        from pneumact.cli.common import load_quietly
        from pneumact.reproduction import reproduce

        check_seed("--seed", seed)
        out = check_out_dir("--out", out)
        parameter_set = load_quietly(params)
        with progress_display("reproducing", bar_per_stage=False) as progress:
            result = reproduce(out, quick=quick, params=parameter_set, seed=seed,
                               call=the_call(ctx), progress=progress, seal_data=seal_data)
    statements = result.tables["paper_statements"]
    for _, row in statements.iterrows():
        held = row["holds for"]
        style = "red" if held.startswith("nowhere") else "green"
        line = Text(f"{row['source']} ({row['statement']}): holds for ")
        line.append(held, style=style)
        line.append(f"; stops: {row['stops']}; noise floor {row['noise floor']}")
        out_console.print(line, soft_wrap=True)
    out_console.print(f"wrote {len(result.files)} files to {out} in {result.wall_time:.1f} s; "
                      f"open {result.report}")
