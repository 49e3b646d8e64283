"""Progress bars with tqdm: drawn on a terminal, silent otherwise.

Used for anything that can take more than a second (planning, bag reading).
Draws on stderr only when it is a TTY, so logs and pipes stay clean.
"""

import sys


class Progress:
    """Context manager around a :class:`tqdm.tqdm` bar on stderr.

    Args:
        total: Number of steps; None: open-ended (a count and its rate, e.g. a stream logged
            until Ctrl-C).
        label: Text before the bar.
        enabled: Force on/off; default: on when the stream is a terminal.
        stream: Where to draw (default ``sys.stderr``).
    """

    def __init__(
        self, total: int | None, label: str = "", enabled: bool | None = None, stream=None
    ):
        self.total = None if total is None else max(int(total), 1)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = (
            enabled
            if enabled is not None
            else bool(getattr(self.stream, "isatty", lambda: False)())
        )
        self.count = 0
        self._bar = None

    def __enter__(self) -> "Progress":
        if self.enabled:
            from tqdm import tqdm

            self._bar = tqdm(
                total=self.total,
                desc=self.label,
                file=self.stream,
                leave=True,
                dynamic_ncols=True,
                mininterval=0.1,
            )
        return self

    def advance(self, steps: int = 1) -> None:
        """Count ``steps`` more done."""
        if self.total is not None:
            steps = min(steps, self.total - self.count)
        self.count += steps
        if self._bar is not None and steps > 0:
            self._bar.update(steps)

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
