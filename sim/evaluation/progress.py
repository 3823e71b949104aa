"""Progress of a long run: a bar with ETA on a terminal, plain timestamped lines when the output goes to a log."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class Progress:
    """Counts done of total; on a terminal a tqdm bar, otherwise a line at most every line_every_s seconds.

    Counts are whole (trials, candidates) or, with a float total, a quantity such as simulated seconds; units is
    the plural the lines print (unit + "s" unless given)."""

    def __init__(
        self,
        total: float,
        initial: float = 0,
        unit: str = "trial",
        label: str = "",
        stream: TextIO | None = None,
        line_every_s: float = 30.0,
        enabled: bool = True,
        units: str | None = None,
    ) -> None:
        self.total, self.done, self.unit, self.label = total, initial, unit, label
        self.units = units or f"{unit}s"
        self.stream = stream or sys.stderr
        self.enabled, self.line_every_s = enabled, line_every_s
        self._initial, self._t0, self._last_line = initial, time.monotonic(), -float("inf")
        self._bar = None
        if enabled and self.stream.isatty():
            from tqdm import tqdm

            self._bar = tqdm(
                total=total, initial=initial, unit=unit, desc=label or None, file=self.stream, smoothing=0.05
            )

    def set_total(self, total: float) -> None:
        """A total found as the run goes (an adaptive run's, as its cells close)."""
        self.total = total
        if self._bar is not None:
            self._bar.total = total
            self._bar.refresh()

    def eta_s(self) -> float | None:
        """[s] seconds left at the rate of this run so far (None before anything finished in it)."""
        ran = self.done - self._initial
        if ran <= 0:
            return None
        return (time.monotonic() - self._t0) / ran * (self.total - self.done)

    def update(self, n: float = 1, note: str = "") -> None:
        self.done += n
        if not self.enabled:
            return
        if self._bar is not None:
            self._bar.update(n)
            if note:
                self._bar.set_postfix_str(note, refresh=False)
            return
        now = time.monotonic()
        if now - self._last_line >= self.line_every_s or self.done >= self.total:
            self._last_line = now
            eta = self.eta_s()
            left = "" if eta is None else f", about {_duration(eta)} left"
            print(
                f"{time.strftime('%H:%M:%S')} {self.label + ': ' if self.label else ''}{_count(self.done)}/"
                f"{_count(self.total)} {self.units}{left}{'; ' + note if note else ''}",
                file=self.stream,
                flush=True,
            )

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


def _count(x: float) -> str:
    return f"{x:.1f}" if isinstance(x, float) else str(x)


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
