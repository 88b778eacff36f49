"""A small progress bar for long work, on stderr, drawn only when stderr is a terminal."""

from __future__ import annotations

import os
import sys
import time


class Progress:
    """
    ``Progress(total, label)``; call :meth:`update` with the amount done so far, :meth:`close` at
    the end. ``total=None`` shows a counter without a bar (open-ended work, e.g. a time budget).

    Draws nothing when stderr is not a terminal (CI logs, pipes) unless ``force=True``, and
    nothing at all when ``MI_BRDFS_NO_PROGRESS`` is set.
    """

    def __init__(self, total: float | None, label: str = "", unit: str = "", force: bool = False,
                 stream=None, width: int = 28):
        self.total, self.label, self.unit, self.width = total, label, unit, width
        self.stream = stream or sys.stderr
        tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.enabled = (tty or force) and not os.environ.get("MI_BRDFS_NO_PROGRESS")
        self.start = time.perf_counter()
        self.done = 0.0
        self._last_draw = 0.0

    def update(self, done: float, note: str = "") -> None:
        self.done = done
        now = time.perf_counter()
        finished = self.total is not None and done >= self.total
        if self.enabled and (now - self._last_draw > 0.1 or finished):
            self._last_draw = now
            self._draw(now, note)

    def _draw(self, now: float, note: str) -> None:
        elapsed = now - self.start
        if self.total:
            frac = min(1.0, self.done / self.total)
            filled = int(round(frac * self.width))
            bar = "█" * filled + "·" * (self.width - filled)
            eta = elapsed / frac * (1 - frac) if frac > 0 else float("nan")
            text = (f"{self.label} [{bar}] {frac:4.0%} {self.done:g}/{self.total:g}{self.unit} "
                    f"{elapsed:5.1f}s, eta {eta:4.1f}s")
        else:
            text = f"{self.label} {self.done:g}{self.unit} {elapsed:5.1f}s"
        if note:
            text += f" {note}"
        self.stream.write("\r" + text + "\x1b[K")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled:
            self._draw(time.perf_counter(), "")
            self.stream.write("\n")
            self.stream.flush()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
