"""``python -m sins.cli``: the ``sins`` command."""

from sins.cli import console

console()
