"""How a command stops on Ctrl-C (SIGINT) and SIGTERM: at once, and honestly.

While a command runs (`handling`, which `cli.main` wraps every command in), the first
SIGINT or SIGTERM raises KeyboardInterrupt in the main thread wherever it is (for SIGTERM
its subclass `Terminated`), and is remembered (`stopped`, `terminated`): the exit status
is then 130 or 143. A second SIGINT raises again (it cuts a clean-up short); a second
SIGTERM is ignored (it does not).

Two rules keep an interrupted command from passing for a finished one:
- Work that is done and is being written (a flight flown, scenarios finished) runs
  inside `deferred()`: a first signal there is remembered (`Deferral.requested`) instead
  of raised, so that what was completed is written whole and marked partial; a second
  one raises at once.
- `raise_if_stopped()` raises again a stop that something swallowed (a library that
  catches KeyboardInterrupt, a solver that handles SIGINT itself): a command calls it
  before it takes what it computed for a result.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Terminated(KeyboardInterrupt):
    """SIGTERM (a scheduler, `kill`, a shutting-down system): raised where Ctrl-C's
    KeyboardInterrupt is, so that every command stops as it does on Ctrl-C; the exit
    status is then 143."""


@dataclass(eq=False)
class Deferral:
    """A stretch of work that a first stop signal does not cut (`deferred`). Compared by
    identity: runs in threads leave their blocks in any order, and one must never take
    another's equal-looking deferral out of the list."""

    armed: bool = True  # deferring now (`arm`: from a later point of the block on)
    requested: bool = False  # a stop signal arrived while armed: mark the result partial

    def arm(self) -> None:
        self.armed = True


_first: int | None = None  # the first stop signal of this command
_terminated = False  # a SIGTERM arrived
_deferrals: list[Deferral] = []
_handling = False  # inside `handling`: a command of the CLI


def stopped() -> bool:
    """Whether a stop signal arrived since the command started."""
    return _first is not None


def terminated() -> bool:
    """Whether a SIGTERM arrived since the command started (exit 143, not 130)."""
    return _terminated


def raise_if_stopped() -> None:
    """Raise KeyboardInterrupt (Terminated after a SIGTERM) if a stop signal arrived,
    even one that was caught and swallowed on the way."""
    if _terminated:
        raise Terminated
    if _first is not None:
        raise KeyboardInterrupt


def _stop(signum: int, frame: object) -> None:
    global _first, _terminated
    first = _first is None
    if signum == signal.SIGTERM:
        if _terminated:
            return  # a second SIGTERM does not cut the clean-up
        _terminated = True
    if first:
        _first = signum
        armed = [d for d in _deferrals if d.armed]
        for deferral in armed:
            deferral.requested = True
        if armed:
            return
    raise Terminated if signum == signal.SIGTERM else KeyboardInterrupt


def _install() -> dict[int, object] | None:
    """Our handler for the stop signals; the previous ones (None: not the main thread,
    where Python delivers signals, so nothing was changed)."""
    if threading.current_thread() is not threading.main_thread():
        return None
    previous = {}
    for signum in STOP_SIGNALS:
        previous[signum] = signal.getsignal(signum)
        signal.signal(signum, _stop)
    return previous


def _restore(previous: dict[int, object] | None) -> None:
    for signum, handler in (previous or {}).items():
        signal.signal(signum, handler if handler is not None else signal.SIG_DFL)


@contextmanager
def handling() -> Iterator[None]:
    """Run a command: the stop signals raise as above, and are forgotten afterwards."""
    global _first, _terminated, _handling
    _first, _terminated, _handling = None, False, True
    previous = _install()
    try:
        yield
    finally:
        _restore(previous)
        _first, _terminated, _handling = None, False, False


@contextmanager
def deferred(*, armed: bool = True, reraise: bool = False) -> Iterator[Deferral]:
    """Finish writing what was completed: a first stop signal inside is remembered
    (`requested`), not raised; a later one (or one after a stop already seen) raises.
    `armed=False`: signals raise as usual until `Deferral.arm()`. `reraise`: the stop
    deferred is raised when the block ends (unless an outer deferral still holds it), so
    that the block is never cut half-way but the caller stops all the same. Outside a
    command (a library call), what arrived is forgotten afterwards but for `requested`."""
    global _first, _terminated
    deferral = Deferral(armed=armed)
    _deferrals.append(deferral)
    previous = None if _handling or _deferrals[:-1] else _install()
    try:
        yield deferral
    finally:
        _deferrals.remove(deferral)
        stop = reraise and deferral.requested and not any(d.armed for d in _deferrals)
        was = Terminated if _terminated else KeyboardInterrupt
        if previous is not None:
            _restore(previous)
            _first, _terminated = None, False
    if stop:
        raise was
