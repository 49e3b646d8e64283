"""CSV tables: read with line-accurate errors, write atomically.

:func:`read_table` gives a :class:`Table` (header, string cells and the file
line of each row) so that every later error can name the file, line and
column; :func:`write_csv` writes floats in shortest round-trip form through an
atomic write.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..exceptions import InvalidSamples
from .atomic import atomic_write_text


@dataclass(frozen=True)
class Table:
    """A parsed CSV: header, string cells and the file line of each row (and of the header)."""

    source: str
    header: list[str]
    rows: list[list[str]]
    lines: list[int]
    header_line: int | None = None

    def column_index(self, name: str) -> int:
        return self.header.index(name)

    def floats(self, names) -> np.ndarray:
        """The named columns as an ``(N, k)`` float array (finite), or :class:`InvalidSamples`."""
        indices = [self.column_index(name) for name in names]
        out = np.empty((len(self.rows), len(indices)))
        for r, (row, line) in enumerate(zip(self.rows, self.lines)):
            for c, (index, name) in enumerate(zip(indices, names)):
                cell = row[index].strip()
                try:
                    value = float(cell)
                except ValueError:
                    raise InvalidSamples(f"column {name!r}: {cell!r} is not a number", self.source, line) from None
                if not np.isfinite(value):
                    raise InvalidSamples(f"column {name!r}: {cell!r} is not finite; expected a finite number", self.source, line)
                out[r, c] = value
        return out


def read_table(path) -> Table:
    """Read a CSV with a header row; ``#`` lines are comments.

    Raises:
        InvalidSamples: missing or empty file, no data rows, duplicated
            columns, or a row with the wrong number of cells.
    """
    path = Path(path)
    source = str(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark (Excel) is not part of the header
    except FileNotFoundError:
        raise InvalidSamples("file not found", source) from None
    except (OSError, UnicodeDecodeError) as error:
        raise InvalidSamples(f"cannot read: {error}", source) from None
    header, header_line, rows, lines = None, None, [], []
    for number, record in enumerate(csv.reader(io.StringIO(text)), start=1):
        if not record or not "".join(record).strip() or record[0].lstrip().startswith("#"):
            continue
        if header is None:
            header, header_line = [cell.strip() for cell in record], number
            duplicates = sorted({name for name in header if header.count(name) > 1})
            if duplicates:
                raise InvalidSamples(f"duplicated column(s) {duplicates} in the header", source, number)
            continue
        if len(record) != len(header):
            raise InvalidSamples(f"{len(record)} cells but the header has {len(header)} columns", source, number)
        rows.append(record)
        lines.append(number)
    if header is None:
        raise InvalidSamples("file is empty; expected a header row and data rows", source)
    if not rows:
        raise InvalidSamples("no data rows after the header", source)
    return Table(source, header, rows, lines, header_line)


def missing_columns(table: Table, wanted, what: str) -> None:
    missing = [name for name in wanted if name not in table.header]
    if missing:
        hints = []
        for name in missing:
            close = [column for column in table.header if column.lower() == name.lower()]
            import difflib  # only for an error message

            close = close or difflib.get_close_matches(name, table.header, n=1)
            if close:
                hints.append(f"{close[0]!r} for {name!r}?")
        hint = (" (did you mean " + ", ".join(hints) + ")") if hints else ""
        raise InvalidSamples(
            f"missing {what} column(s) {missing}{hint}; the header has {table.header}",
            table.source,
            table.header_line if table.header_line is not None else table.lines[0] - 1,
        )


def format_float(value: float) -> str:
    """Shortest text that reads back as the same float."""
    return repr(float(value))


def write_csv(path, header, rows) -> Path:
    """Write rows (sequences of str or numbers) under a header, atomically."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    for row in rows:
        writer.writerow([format_float(cell) if isinstance(cell, (float, np.floating)) else cell for cell in row])
    return atomic_write_text(path, buffer.getvalue())
