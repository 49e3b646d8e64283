"""Time columns: ``t`` [s], its aliases, and units converted only where the column name says
them.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.exceptions import InvalidSamples
from ftkin.io.samples_csv import load_samples

ROWS = [
    (0.0, 10.0, 0.0, 0.0, 1.0, 2.0, -9.0, 0.1, 0.2, 0.0),
    (1.0, 20.0, 90.0, 0.0, 1.5, 2.0, -3.0, 0.0, 0.3, 0.0),
    (2.0, 30.0, 0.0, 90.0, -8.0, 2.0, 1.0, 0.2, 0.0, 0.1),
]


def _write(path, time_header):
    text = f"{time_header},alpha,beta,gamma,fx,fy,fz,mx,my,mz\n"
    text += "".join(
        ",".join(
            f"{v:g}" for v in (row[0] * 1000.0 if "ms" in time_header else row[0], *row[2:], 0.0)
        )
        + "\n"
        for row in ROWS
    )
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("header", "expected"),
    [
        ("t", [0, 1, 2]),
        ("time", [0, 1, 2]),
        ("timestamp", [0, 1, 2]),
        ("t_ms", [0, 1, 2]),
        ("time_ms", [0, 1, 2]),
    ],
)
def test_time_aliases(tmp_path, header, expected):
    loaded = load_samples(_write(tmp_path / "s.csv", header))
    np.testing.assert_allclose(loaded.samples.times, expected)


def test_two_time_columns_are_ambiguous(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text("time,stamp,alpha,beta,gamma,fx,fy,fz,mx,my,mz\n0,0,0,0,0,1,2,3,0,0,0\n")
    with pytest.raises(InvalidSamples, match=r"several time columns \['time', 'stamp'\]"):
        load_samples(path)


def test_a_textual_timestamp_column_is_left_alone(tmp_path, caplog):
    import logging

    path = tmp_path / "s.csv"
    path.write_text(
        "timestamp,alpha,beta,gamma,fx,fy,fz,mx,my,mz\n"
        "2026-11-29T10:00:00,0,0,0,1,2,-9,0.1,0.2,0\n2026-11-29T10:00:30,90,0,0,1.5,2,-3,0,0.3,0\n"
        "2026-11-29T10:01:00,0,90,0,-8,2,1,0.2,0,0.1\n"
    )
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        loaded = load_samples(path)
    assert loaded.samples.times is None
    assert "column 'timestamp' is not numbers of seconds" in caplog.text


def test_times_that_are_plainly_not_seconds_are_refused_naming_time_unit(tmp_path):
    """Nanoseconds since the epoch in an alias or in t: refused, naming --time-unit ns; with it,
    seconds since the epoch (the stamps' own spacing, 30 s, kept exactly)."""
    from ftkin.io.column_spelling import ColumnSpelling

    rows = "0,0,0,1,2,-9,0.1,0.2,0\n90,0,0,1.5,2,-3,0,0.3,0\n0,90,0,-8,2,1,0.2,0,0.1\n"
    stamps = ["1764410400000000000", "1764410430000000000", "1764410460000000000"]
    text = "".join(f"{s},{r}\n" for s, r in zip(stamps, rows.splitlines()))
    for name in ("stamp", "t"):
        path = tmp_path / f"{name}.csv"
        path.write_text(f"{name},alpha,beta,gamma,fx,fy,fz,mx,my,mz\n" + text)
        with pytest.raises(InvalidSamples, match=r"line 4: .*not seconds.*--time-unit ns"):
            load_samples(path)
        times = load_samples(path, spelling=ColumnSpelling(time_unit="ns")).samples.times
        np.testing.assert_allclose(np.diff(times), [30.0, 30.0], rtol=0, atol=1e-6)
        np.testing.assert_allclose(times[0], 1764410400.0, rtol=1e-15)
