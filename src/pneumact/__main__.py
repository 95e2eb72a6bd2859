"""``python -m pneumact`` and the ``pneumact`` command: the command line.

Ctrl-C is honoured from the first instant: while the command line is still being
imported (typer, rich, numpy: about half a second) an interrupt exits 130 with one line,
as it does once a command runs, not with a traceback.
"""

from __future__ import annotations

import sys

#: The exit code of an interrupted command (128 + SIGINT), as every command uses.
EXIT_INTERRUPTED = 130


def main() -> None:
    """Import the command line and run it; an interrupt during the import exits 130."""
    try:
        from pneumact.cli import app
    except KeyboardInterrupt:
        sys.stderr.write("stopped: interrupted\n")
        raise SystemExit(EXIT_INTERRUPTED) from None
    app()


if __name__ == "__main__":
    main()
