"""Progress bars: tqdm on a terminal, nothing at all otherwise."""

from __future__ import annotations

import io

from ftkin.progress import Progress


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_silent_when_the_stream_is_not_a_terminal():
    stream = io.StringIO()
    with Progress(5, "planning", stream=stream) as bar:
        for _ in range(5):
            bar.advance()
    assert stream.getvalue() == "" and bar.count == 5


def test_tqdm_bar_on_a_terminal():
    stream = _Terminal()
    with Progress(4, "sampling poses", stream=stream) as bar:
        bar.advance(3)
        bar.advance(5)  # clamped to the total
    text = stream.getvalue()
    assert "sampling poses" in text and "4/4" in text and "100%" in text
    assert bar.count == 4


def test_forced_off_on_a_terminal():
    stream = _Terminal()
    with Progress(3, "x", enabled=False, stream=stream) as bar:
        bar.advance()
    assert stream.getvalue() == ""
