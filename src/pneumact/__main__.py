"""``python -m pneumact``: the command line."""

from pneumact.cli import app

app()
