"""Screenshots of HTML pages with headless Chromium (for ``ftkin view --png``).

meshcat's static page (``static_html()``) renders completely in headless
Chromium in a couple of seconds; the live server URL does not (the scene
arrives over a websocket after the screenshot is taken), so ftkin always
screenshots a page saved to a file.

Chromium is a system program, not a Python package: on Debian/Ubuntu
``apt-get install chromium``; or point ``FTKIN_CHROMIUM`` at a
Chrome/Chromium executable.
"""

import os
import shutil
import signal
import subprocess
import tempfile
from pathlib import Path

from ..exceptions import FtkinError, InvalidInput
from ..io.atomic import atomic_write_bytes, atomic_write_text

CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
"""Executable names tried, in order, when ``FTKIN_CHROMIUM`` is not set."""

QUIET_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-sync",
    "--hide-scrollbars",
)
"""Flags for a headless run on a machine without display or internet."""


class BrowserError(FtkinError):
    """Headless Chromium is missing or failed; the message says how to fix it."""


def find_chromium() -> str | None:
    """Path of a Chromium/Chrome executable (``FTKIN_CHROMIUM`` first), or None."""
    override = os.environ.get("FTKIN_CHROMIUM")
    if override:
        return shutil.which(override) or (override if os.access(override, os.X_OK) else None)
    return next(filter(None, map(shutil.which, CANDIDATES)), None)


def screenshot_file(page, png_path, window_size=(1024, 768), timeout: float = 60.0) -> Path:
    """Render an HTML file to a PNG with headless Chromium; returns the PNG path.

    Args:
        page: The HTML file to load.
        png_path: Where to write the screenshot (atomically).
        window_size: Viewport ``(width, height)`` [px].
        timeout: Seconds before Chromium is stopped [s].

    Raises:
        BrowserError: Chromium is missing, fails, times out or writes no image.
    """
    page = Path(page).resolve()
    if not page.is_file():
        raise InvalidInput(f"cannot screenshot {page}: no such file")
    try:
        width, height = (int(v) for v in window_size)
    except (TypeError, ValueError):
        width = height = 0
    if width <= 0 or height <= 0:
        raise InvalidInput(
            f"window_size must be two positive pixel counts (width, height), got {window_size!r}"
        )
    executable = find_chromium()
    if executable is None:
        raise BrowserError(
            "headless Chromium is needed for the screenshot but was not found; install it "
            "(Debian/Ubuntu: apt-get install chromium) or set FTKIN_CHROMIUM to a Chrome/Chromium "
            "executable"
        )
    with tempfile.TemporaryDirectory(prefix="ftkin-chromium-") as scratch:
        shot = Path(scratch) / "shot.png"
        command = [
            executable,
            *QUIET_FLAGS,
            f"--screenshot={shot}",
            f"--window-size={width},{height}",
            f"--user-data-dir={Path(scratch) / 'profile'}",
            page.as_uri(),
        ]
        try:  # in its own process group: on timeout stop the group (Chromium forks helpers)
            process = subprocess.Popen(
                command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True
            )
        except OSError as error:
            raise BrowserError(f"cannot start Chromium ({executable}): {error}") from None
        try:
            _, stderr = process.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()
            raise BrowserError(
                f"Chromium did not finish the screenshot within {timeout:g} s"
            ) from None
        if process.returncode != 0:
            tail = stderr.decode("utf-8", "replace").strip().splitlines()[-3:]
            raise BrowserError(
                f"Chromium failed (exit code {process.returncode}): " + " | ".join(tail)
            )
        if not shot.is_file() or shot.stat().st_size == 0:
            raise BrowserError(f"Chromium ({executable}) wrote no screenshot of {page}")
        return atomic_write_bytes(png_path, shot.read_bytes())


def screenshot_html(html: str, png_path, window_size=(1024, 768), timeout: float = 60.0) -> Path:
    """Render an HTML string to a PNG (saved to a temporary file first); returns the PNG path."""
    with tempfile.TemporaryDirectory(prefix="ftkin-page-") as scratch:
        page = atomic_write_text(Path(scratch) / "page.html", html)
        return screenshot_file(page, png_path, window_size, timeout)
