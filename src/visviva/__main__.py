"""``python -m visviva`` runs the command-line interface."""

from .cli.main import main

main()
