"""``python -m pneumact`` and the ``pneumact`` command: the command line.

Ctrl-C is honoured from the first instant: while the command line is still being
imported (typer, rich, numpy: about half a second) an interrupt exits 130 with one line,
as it does once a command runs, not with a traceback. After a Ctrl-C the process ends
at once, once the command has unwound (its partial results kept, its staging folders
and locks released, all by the main thread): without waiting for a worker thread still
busy in compiled code (a kernel being compiled cannot be interrupted from Python, and
the interpreter would wait for it) nor for the interpreter's teardown (2-3 s on a
loaded machine, which alone broke the 2 s promise).
"""

from __future__ import annotations

import os
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
    from pneumact.progress import leave_stopped_work

    leave_stopped_work()
    try:
        app()
    except SystemExit as exit_:
        if exit_.code == EXIT_INTERRUPTED:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(EXIT_INTERRUPTED)  # no wait for threads, no interpreter teardown
        raise


if __name__ == "__main__":
    main()
