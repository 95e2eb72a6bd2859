"""``python -m pneumact`` and the ``pneumact`` command: the command line.

Ctrl-C is honoured from the first instant: while the command line is still being
imported (typer, rich, numpy: about half a second) an interrupt exits 130 with one line,
as it does once a command runs, not with a traceback. After a Ctrl-C the process ends
at once even if a worker thread is still busy in compiled code (a kernel being compiled
cannot be interrupted from Python, and the interpreter would wait for it at exit):
everything the command keeps was written by the main thread before it exits.
"""

from __future__ import annotations

import os
import sys
import threading

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
        if exit_.code == EXIT_INTERRUPTED and _busy_threads():
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(EXIT_INTERRUPTED)  # not waiting for threads left in compiled code
        raise


def _busy_threads() -> bool:
    """Whether a thread other than the main one is still running (and would hold the
    interpreter's exit)."""
    main_thread = threading.main_thread()
    return any(t is not main_thread and t.is_alive() and not t.daemon
               for t in threading.enumerate())


if __name__ == "__main__":
    main()
