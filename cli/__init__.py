"""gliderplan.cli: the `gliderplan` command; each subcommand lives in its own module."""
