"""One text progress bar for long loops (batch studies, multistart mappings).

The line is formatted by :func:`tqdm.tqdm.format_meter` (counts, percent, rate, ETA, elapsed
time); this class only decides when to draw it. On a terminal the bar is redrawn in place at
most ten times a second; on any other stream (a log file, a pipe) a full line is written at
most every ``log_interval_s`` seconds, and the final state is written exactly once.
"""

from __future__ import annotations

import math
import sys
import time
from typing import TextIO

_FORMAT = ("{desc} [{bar}] {n_fmt}/{total_fmt} {percentage:3.0f}% {rate_noinv_fmt} "
           "ETA {remaining} elapsed {elapsed}{postfix}")


class ProgressBar:
    """A progress bar on a text stream (stderr by default); silent unless ``enabled``.

    Args:
        total: Number of steps expected.
        label: Text in front of the bar.
        enabled: Draw anything at all.
        stream: Where to draw (default: ``sys.stderr``).
        width: Characters of the bar itself.
        log_interval_s: Least time between two lines on a stream that is not a terminal [s].
    """

    def __init__(self, total: int, label: str, enabled: bool = True,
                 stream: TextIO | None = None, width: int = 24, log_interval_s: float = 10.0):
        self.total, self.label, self.enabled, self.width = max(int(total), 0), label, enabled, width
        self.stream: TextIO = stream or sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.log_interval_s = log_interval_s
        self.done = self.failed = 0
        self.best: float | None = None
        self.start = time.perf_counter()
        self._last = -math.inf
        self._finished = False

    def line(self) -> str:
        """The current state as one line of text."""
        from tqdm import tqdm

        extra = []
        if self.best is not None:
            extra.append(f"best {self.best:.3e}")
        if self.failed:
            extra.append(f"{self.failed} failed")
        bar_format = _FORMAT.replace("{bar}", "{bar:%d}" % self.width)
        return tqdm.format_meter(self.done, self.total or None, time.perf_counter() - self.start,
                                 prefix=self.label, ascii=".#", unit="", bar_format=bar_format,
                                 postfix=", ".join(extra) or None)

    def update(self, done: int = 1, failed: int = 0, best: float | None = None) -> None:
        """Count finished steps (``failed`` of them failed), note the best loss so far, redraw.

        Args:
            done: Steps finished since the last call.
            failed: How many of them failed.
            best: Best objective value so far, shown after the counts (optional).
        """
        self.done += done
        self.failed += failed
        if best is not None:
            self.best = float(best)
        self._draw(final=self.done >= self.total)

    def close(self) -> None:
        """Draw the final state (once, however often it is called)."""
        self._draw(final=True)

    def _draw(self, final: bool) -> None:
        if not self.enabled or self._finished:
            return
        now = time.perf_counter()
        interval = 0.1 if self.tty else self.log_interval_s
        if not final and now - self._last < interval:
            return
        self._last = now
        if self.tty:
            self.stream.write("\r" + self.line() + ("\n" if final else ""))
        else:
            self.stream.write(self.line() + "\n")
        self.stream.flush()
        self._finished = final
