"""Entry point of the `gliderplan` command.

Each subcommand is a module in this package named after it, with ``ORDER`` (its
place in --help), ``add_arguments(parser)`` and ``run(args) -> int``; the first line
of its docstring is its help. A subcommand parses, calls the library and prints; the
errors the library raises (`contract.errors.GliderplanError`) become messages here only
(`report`). Only the module of the subcommand that runs is imported (all of them for
--help or a mistyped command), and subcommand modules import heavy libraries (cvxpy,
pandas) inside ``run`` only, so that ``gliderplan check`` starts fast.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import select
import sys
from collections.abc import Callable, Sequence
from types import ModuleType
from typing import TextIO

import gliderplan.cli
from gliderplan.contract import ExitCode, interrupts
from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.files import OutputFileError
from gliderplan.contract.interrupts import Terminated  # noqa: F401 (cli.main.Terminated)


def subcommands(only: str | None = None) -> dict[str, ModuleType]:
    """Subcommand name -> module, in --help order; just `only` when that names one.
    A module's name is its command's, with `_` for `-` (compare_sbc: compare-sbc)."""
    names = [info.name for info in pkgutil.iter_modules(gliderplan.cli.__path__)
             if not info.name.startswith("_")]
    wanted = only.replace("-", "_") if only is not None else None
    found = [m for m in map(_module, [wanted] if wanted in names else names)
             if _is_subcommand(m)]
    if only is not None and not found:  # not a subcommand (a mistake, or a helper module)
        return subcommands()
    return {m.__name__.rsplit(".", 1)[1].replace("_", "-"): m
            for m in sorted(found, key=lambda m: m.ORDER)}


def _module(name: str) -> ModuleType:
    return importlib.import_module(f"gliderplan.cli.{name}")


def _is_subcommand(module: ModuleType) -> bool:
    return hasattr(module, "ORDER") and hasattr(module, "run")


class _Parser(argparse.ArgumentParser):
    """argparse, but usage errors exit 2 through the same path as ours."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.print_usage(sys.stderr)
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        raise SystemExit(ExitCode.USAGE)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser; with `command`, only that subcommand's (if it is one)."""
    parser = _Parser(prog="gliderplan", description="Mission language, power-aware planner, "
                     "C runtime and simulator for Slocum-class underwater gliders.")
    parser.add_argument("--version", action="version", version=f"gliderplan {version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name, module in subcommands(command).items():
        help_text = module.__doc__.splitlines()[0].split(": ", 1)[-1]
        sub_parser = sub.add_parser(name, help=help_text, description=help_text)
        module.add_arguments(sub_parser)
        sub_parser.set_defaults(_run=module.run)
    return parser


def _stop_code() -> ExitCode:
    return ExitCode.TERMINATED if interrupts.terminated() else ExitCode.INTERRUPTED


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return the exit code (`contract.ExitCode`)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["--version"]:
        print(f"gliderplan {version()}")
        return ExitCode.OK
    with interrupts.handling():  # from here on a stop signal stops it with 130 or 143
        try:
            # The top-level parser has no option but --help, so a first word is the command.
            command = argv[0] if argv and not argv[0].startswith("-") else None
            args = build_parser(command).parse_args(argv)
        except KeyboardInterrupt:
            return _stop_code()
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    """Run the parsed command: SIGINT and SIGTERM stop it (contract.interrupts: exit 130,
    143); its errors become a message and an exit code here."""
    real_stdout, sys.stdout = sys.stdout, _Stdout(sys.stdout)
    try:
        code = int(args._run(args))
        sys.stdout.flush()  # here, where a reader that went away is handled below
        # a stop signal that arrived while the command ran stops it with 130 or 143, even
        # one that its last moments swallowed: the outputs then say what they hold
        return _stop_code() if code == ExitCode.INTERRUPTED or interrupts.stopped() else code
    except GliderplanError as err:
        if getattr(args, "json", False):  # the error as JSON where the result would be
            print_json(err.to_json(args.command))
        return report(args.command, err)
    except KeyboardInterrupt:
        print(f"gliderplan {args.command}: "
              f"{'terminated' if interrupts.terminated() else 'interrupted'}", file=sys.stderr)
        return _stop_code()
    except Exception as err:  # a bug: say so plainly; the traceback only on request
        if isinstance(err, BrokenPipeError) and _stdout_reader_gone():
            # Like `cat | head`: no message, and nothing more to print. Python flushes
            # stdout once more at exit, which would fail again: point it at /dev/null.
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return ExitCode.BROKEN_PIPE
        if os.environ.get("GLIDERPLAN_DEBUG"):
            raise
        said = f"internal error: {type(err).__name__}: {err}"
        if getattr(args, "json", False):
            print_json(GliderplanError(said).to_json(args.command) | {"exit_code": 70})
        print(f"gliderplan {args.command}: {said}\n"
              "  (this is a bug in gliderplan; rerun with GLIDERPLAN_DEBUG=1 for details)",
              file=sys.stderr)
        return ExitCode.INTERNAL
    finally:
        sys.stdout = real_stdout


def print_json(data: object) -> None:
    """A command's --json result on stdout (docs/json.md): indented, no NaN (null)."""
    import json

    print(json.dumps(_no_nan(data), indent=2))


def _no_nan(data: object) -> object:
    """`data` with every float that is not finite as None: JSON has no NaN."""
    import math

    if isinstance(data, float) and not math.isfinite(data):
        return None
    if isinstance(data, dict):
        return {k: _no_nan(v) for k, v in data.items()}
    if isinstance(data, list | tuple):
        return [_no_nan(v) for v in data]
    return data


def version() -> str:
    """The installed gliderplan's version (its distribution's metadata)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as installed

    try:
        return installed("gliderplan")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "unknown (not installed)"


class _Stdout:
    """sys.stdout while a command runs: a write that fails for want of space or of a
    device (stdout on a full disk, /dev/full) is a result that cannot be written where
    asked, as for -o (OutputFileError, exit 2), and what is still buffered is dropped
    rather than failing again at exit. A reader that went away stays a BrokenPipeError."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def _guarded(self, call: Callable[[], object]) -> object:
        try:
            return call()
        except BrokenPipeError:
            raise
        except OSError as err:
            os.dup2(os.open(os.devnull, os.O_WRONLY), self._stream.fileno())
            raise OutputFileError(f"cannot write the output (stdout): "
                                  f"{err.strerror or err}") from None

    def write(self, text: str) -> object:
        return self._guarded(lambda: self._stream.write(text))

    def flush(self) -> object:
        return self._guarded(self._stream.flush)

    def __getattr__(self, name: str) -> object:
        return getattr(self._stream, name)


def _stdout_reader_gone() -> bool:
    """True if stdout is a pipe whose reading end is closed (poll says POLLERR then)."""
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(events & select.POLLERR for _, events in poller.poll(0))
    except (AttributeError, OSError, ValueError):  # no stdout, or no poll on this system
        return False


def report(command: str, err: GliderplanError) -> ExitCode:
    """The one place an error becomes a message: its details (a mission's diagnostics),
    then one line naming the command; the exit code the error carries."""
    if err.details:
        print(err.details, file=sys.stderr)
    print(f"gliderplan {command}: error: {err}", file=sys.stderr)
    return err.exit_code


def entry() -> None:
    try:
        code = main()
    except KeyboardInterrupt:  # Ctrl-C before the command started, or as it ended
        code = ExitCode.INTERRUPTED
    sys.exit(code)
