"""Progress reports and cancellation for Glint's long loops (``test_break`` style).

A loop calls :meth:`Progress.step` once per item. The object asks ``should_stop``
(e.g. a render's ``test_break`` or an operator's cancel flag) on every step and
raises :class:`Cancelled`; it calls ``report(fraction, message)`` at most every
``interval`` seconds (and once more at the end if it reported before), so
printing to a log stays cheap and quick work prints nothing.
"""
from __future__ import annotations

import contextlib
import time
from typing import Callable, Dict, Optional


class Cancelled(Exception):
    """The user (or the render) asked Glint to stop."""


class Progress:
    def __init__(self, total: int, report: Optional[Callable[[float, str], None]] = None,
                 should_stop: Optional[Callable[[], bool]] = None, interval: float = 1.0,
                 clock: Callable[[], float] = time.monotonic, label: str = ""):
        self.total = max(int(total), 0)
        self.done = 0
        self._report = report
        self._should_stop = should_stop
        self._interval = interval
        self._clock = clock
        self._last = clock()
        self._reported = False
        self.label = label

    @property
    def fraction(self) -> float:
        return 1.0 if self.total == 0 else min(self.done / self.total, 1.0)

    def check(self) -> None:
        if self._should_stop is not None and self._should_stop():
            raise Cancelled(f"{self.label or 'work'} cancelled at {self.done}/{self.total}")

    def step(self, n: int = 1, message: str = "") -> None:
        self.done += n
        self.check()
        now = self._clock()
        due = now - self._last >= self._interval
        # The closing 100% only follows earlier reports: quick work stays quiet.
        final = self.done >= self.total and self._reported
        if self._report is not None and (due or final):
            self._last = now
            self._reported = True
            self._report(self.fraction, message)


class Timings:
    """Named wall-clock durations in milliseconds, in the order they were taken."""

    def __init__(self, clock: Callable[[], float] = time.perf_counter):
        self._clock = clock
        self.ms: Dict[str, float] = {}

    @contextlib.contextmanager
    def measure(self, name: str):
        """Time the ``with`` block (added to earlier spans of the same name)."""
        t0 = self._clock()
        try:
            yield
        finally:
            self.ms[name] = self.ms.get(name, 0.0) + (self._clock() - t0) * 1000.0

    def total(self) -> float:
        return sum(self.ms.values())

    def summary(self) -> str:
        parts = [f"{k} {v:.1f} ms" for k, v in self.ms.items()]
        return ", ".join(parts) + f" (total {self.total():.1f} ms)"
