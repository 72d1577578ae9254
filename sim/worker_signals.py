"""Imported first by the fork server that starts the local Dask cluster's workers: its
workers never take the terminal's Ctrl-C (one that did died printing its traceback);
the process that started them takes it and closes them. The fork server keeps the
disposition it had after its preloads and its children inherit it, so this process
never has to ignore the signal itself (a Ctrl-C ignored there would be lost)."""

import signal

signal.signal(signal.SIGINT, signal.SIG_IGN)
