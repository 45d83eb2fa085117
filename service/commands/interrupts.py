"""Ctrl-C wherever it lands: the user's interrupt, never a traceback.

Python raises a SIGINT's KeyboardInterrupt in whatever Python code runs when it arrives.
Inside a C extension's call back into Python -- h5py's attribute iteration, the weak
references of its object registry -- that code cannot take it:

- a callback that returns with the exception set becomes ``SystemError: <cyfunction
  FastRLock.__exit__ ...> returned a result with an exception set``, with the interrupt
  as its cause (``balloon db seal`` stopped at 25 s printed that traceback, exit 1);
- an exception in a weak-reference callback is "ignored": Python prints it with its
  traceback through ``sys.unraisablehook`` and the command runs on as if Ctrl-C had not
  been pressed (the seal then finished and exited 0).

``caused_by_interrupt`` tells the first from a genuine error; ``interrupts_kept`` hands the
second back to the main thread as Ctrl-C again, where it stops the command.
"""

from __future__ import annotations

import _thread
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

REDELIVERY_DELAY_S = 0.01  # the hook returns within it; a person sees no delay


def caused_by_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` is a KeyboardInterrupt or was raised because of one (one in its
    chain of causes and contexts)."""
    seen: set[int] = set()
    link: BaseException | None = exc
    while link is not None and id(link) not in seen:
        if isinstance(link, KeyboardInterrupt):
            return True
        seen.add(id(link))
        link = link.__cause__ or link.__context__
    return False


@contextmanager
def interrupts_kept() -> Iterator[None]:
    """Within the block, a KeyboardInterrupt Python would print as "Exception ignored"
    is raised again in the main thread, as a SIGINT is (nothing when SIGINT is ignored),
    from a helper thread once the hook has returned (raised in the hook, or while it
    waits for a thread to start, it would be "ignored" once more). One
    kept but not raised yet when the block ends is raised there. Every other unraisable
    exception goes to the hook that was there."""
    previous = sys.unraisablehook
    kept = threading.Event()
    lock = threading.Lock()

    def deliver() -> None:
        with lock:
            if kept.is_set():
                kept.clear()
                _thread.interrupt_main()

    def hook(unraisable: sys.UnraisableHookArgs) -> None:
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            kept.set()
            timer = threading.Timer(REDELIVERY_DELAY_S, deliver)
            timer.daemon = True
            timer.start()
            return
        previous(unraisable)

    sys.unraisablehook = hook
    try:
        yield
    finally:
        sys.unraisablehook = previous
        with lock:
            undelivered = kept.is_set()
            kept.clear()
    if undelivered:
        raise KeyboardInterrupt
