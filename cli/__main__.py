"""`python -m gliderplan.cli` runs the command line."""

from gliderplan.cli.main import entry

entry()
