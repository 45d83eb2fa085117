"""What the emulator computed for a design, kept for the next question about that design.

A query's cost is almost all in the design's own curve: its node GPs, the range and sign
models (about 2.6 of 3.1 ms for 100 pressures with bands on a slow core); reading that
curve at the asked pressures, volumes or times is the rest. Users ask the same design
again and again -- other pressures, the volume axis, a plot, the explorer's slider, an
inverse search revisiting a candidate -- so the last designs' curves (MEMO_SIZE entries) are kept,
keyed by everything they depend on (the group, the unit-cube coordinates' exact bytes, the
length scale, the band's z, what was asked). A kept value's arrays are made read-only, so
no caller can change what the next caller gets. Thread-safe (the service answers from
several threads); two threads may compute the same design at once and keep either result,
which are equal.

    memo = DesignMemo()
    value = memo.get_or_make(key, lambda: expensive(...))
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import fields, is_dataclass
from typing import TypeVar

import numpy as np

# entries, about two per design asked (~16 kB an entry: at most ~65 MB beside the loaded
# emulator's ~1 GB). One calibration asks for about 2,200 designs' tables along its
# effects' nodes and comes back to them: with 256 entries it took ~8 % longer.
MEMO_SIZE = 4096
T = TypeVar("T")


class DesignMemo:
    """A least-recently-used store of per-design results (``get_or_make``)."""

    def __init__(self, size: int = MEMO_SIZE) -> None:
        self.size = size
        self._items: OrderedDict[Hashable, object] = OrderedDict()
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._items)

    def clear(self) -> None:
        """Forget every kept value (a benchmark's first query of a design)."""
        with self._lock:
            self._items.clear()

    def get(self, key: Hashable) -> object | None:
        """The value kept for ``key`` (marked as just used), or None."""
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key]
        return None

    def get_or_make(self, key: Hashable, make: Callable[[], T]) -> T:
        """The value kept for ``key``, else ``make()``, kept (read-only) and returned; an
        exception from ``make`` keeps nothing."""
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key]  # type: ignore[return-value]
        value = make()
        _freeze(value)
        with self._lock:
            self._items[key] = value
            self._items.move_to_end(key)
            while len(self._items) > self.size:
                self._items.popitem(last=False)
        return value


def _freeze(value: object) -> None:
    """Make every numpy array in ``value`` (a dataclass, tuple or array, nested)
    read-only; other objects are left as they are."""
    if isinstance(value, np.ndarray):
        value.flags.writeable = False
    elif isinstance(value, tuple):
        for v in value:
            _freeze(v)
    elif is_dataclass(value) and not isinstance(value, type):
        for f in fields(value):
            v = getattr(value, f.name)
            if isinstance(v, np.ndarray | tuple):
                _freeze(v)
