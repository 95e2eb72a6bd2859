"""``python -m pneumact.cli``: the command line."""

from pneumact.cli import app

app()
