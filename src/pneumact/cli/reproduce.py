"""``pneumact reproduce [--quick] [--out DIR]``: the whole seed paper, one folder."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from pneumact.checks import check_out_dir, check_seed
from pneumact.cli.common import ParamsOption, err_console, out_console, the_call, user_errors


def reproduce_command(
    ctx: typer.Context,
    params: ParamsOption = "vgt-paper",
    quick: Annotated[bool, typer.Option("--quick", help="Small campaign and samples (for "
                                                        "tests); rough numbers.")] = False,
    seed: Annotated[int, typer.Option(help="Seed of the synthetic noise and samples "
                                             "(>= 0).")] = 0,
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-paper"),
) -> None:
    """Reproduce the paper: Table I, Figs. 2, 3, 5 and 6, the identification on a
    synthetic campaign, the sensitivity ranking against the paper's statements; writes
    OUT/index.html with every table and figure (also as CSV and PNG)."""
    with user_errors():
        from pneumact.cli.common import load_quietly
        from pneumact.reproduction import reproduce

        check_seed("--seed", seed)
        out = check_out_dir("--out", out)
        parameter_set = load_quietly(params)
        with err_console.status("reproducing") as status:
            result = reproduce(out, quick=quick, params=parameter_set, seed=seed,
                               call=the_call(ctx),
                               progress=lambda label: status.update(f"reproducing: {label}"))
    statements = result.tables["paper_statements"]
    for _, row in statements.iterrows():
        verdict = "[green]agrees[/]" if row["agrees"] else "[red]disagrees[/]"
        out_console.print(f"{row['statement']}: {verdict}: {row['ours']}")
    out_console.print(f"wrote {len(result.files)} files to {out} in {result.wall_time:.1f} s; "
                      f"open {result.report}")
