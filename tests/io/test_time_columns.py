"""Time columns: ``t`` [s], its aliases, and units converted only where the column name says them."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.exceptions import InvalidSamples
from ftkin.io.samples_csv import load_samples

ROWS = [(0.0, 10.0, 0.0, 0.0, 1.0, 2.0, -9.0, 0.1, 0.2, 0.0), (1.0, 20.0, 90.0, 0.0, 1.5, 2.0, -3.0, 0.0, 0.3, 0.0),
        (2.0, 30.0, 0.0, 90.0, -8.0, 2.0, 1.0, 0.2, 0.0, 0.1)]


def _write(path, time_header):
    text = f"{time_header},alpha,beta,gamma,fx,fy,fz,mx,my,mz\n"
    text += "".join(",".join(f"{v:g}" for v in (row[0] * 1000.0 if "ms" in time_header else row[0], *row[2:], 0.0))
                    + "\n" for row in ROWS)
    path.write_text(text)
    return path


@pytest.mark.parametrize(("header", "expected"), [("t", [0, 1, 2]), ("time", [0, 1, 2]), ("timestamp", [0, 1, 2]),
                                                  ("t_ms", [0, 1, 2]), ("time_ms", [0, 1, 2])])
def test_time_aliases(tmp_path, header, expected):
    loaded = load_samples(_write(tmp_path / "s.csv", header))
    np.testing.assert_allclose(loaded.samples.times, expected)


def test_two_time_columns_are_ambiguous(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text("time,stamp,alpha,beta,gamma,fx,fy,fz,mx,my,mz\n0,0,0,0,0,1,2,3,0,0,0\n")
    with pytest.raises(InvalidSamples, match=r"several time columns \['time', 'stamp'\]"):
        load_samples(path)
