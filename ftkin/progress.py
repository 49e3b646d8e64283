"""A minimal progress bar: drawn on a terminal, silent otherwise.

Used for anything that can take more than a second (planning, bag reading).
Writes to stderr only when it is a TTY, so logs and pipes stay clean.
"""

from __future__ import annotations

import sys
import time


class Progress:
    """Context manager drawing ``label [#####.....] k/n`` on stderr.

    Args:
        total: Number of steps.
        label: Text before the bar.
        enabled: Force on/off; default: on when stderr is a terminal.
        stream: Where to draw (default ``sys.stderr``).
    """

    def __init__(self, total: int, label: str = "", enabled: bool | None = None, stream=None):
        self.total = max(int(total), 1)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled if enabled is not None else bool(getattr(self.stream, "isatty", lambda: False)())
        self.count = 0
        self._last_draw = 0.0

    def __enter__(self) -> Progress:
        self._draw(force=True)
        return self

    def advance(self, steps: int = 1) -> None:
        """Count ``steps`` more done; redraws at most 10 times a second."""
        self.count = min(self.count + steps, self.total)
        self._draw()

    def _draw(self, force: bool = False) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if not force and now - self._last_draw < 0.1 and self.count < self.total:
            return
        self._last_draw = now
        width = 30
        filled = int(width * self.count / self.total)
        self.stream.write(f"\r{self.label} [{'#' * filled}{'.' * (width - filled)}] {self.count}/{self.total}")
        self.stream.flush()

    def __exit__(self, *exc) -> None:
        if self.enabled:
            self._draw(force=True)
            self.stream.write("\n")
            self.stream.flush()
