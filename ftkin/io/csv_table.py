"""CSV tables: read with line-accurate errors, write atomically.

:func:`read_table` gives a :class:`Table` (header, string cells and the file
line of each row) so that every later error can name the file, line and
column; :func:`write_csv` writes floats in shortest round-trip form through an
atomic write.
"""

import csv
import io
import logging
import re
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..exceptions import InvalidSamples
from ..options import float_text
from .atomic import atomic_write_text

logger = logging.getLogger(__name__)

DELIMITER_NAMES = {",": "comma", ";": "semicolon", "\t": "tab"}
_DECIMAL_COMMA = re.compile(r"^[+-]?\d+,\d+(?:[eE][+-]?\d+)?$")


def _not_a_number(name: str, cell: str) -> str:
    if _DECIMAL_COMMA.match(cell):
        return (
            f"column {name!r}: {cell!r} has a decimal comma; write numbers with a decimal point "
            f"({cell.replace(',', '.')!r})"
        )
    shown = cell if len(cell) <= 40 else cell[:40] + "..."
    return f"column {name!r}: {shown!r} is not a number"


@dataclass(frozen=True)
class Table:
    """A parsed CSV: header, string cells and the file line of each row (and of the header).

    ``accel_unit``: the unit its ``ax,ay,az`` are already in when the table's maker converted them
    (the join of several files: ``"m/s^2"``), so that a reader does not convert them again; None
    for a file as read (its reader is told the unit, ``--accel-unit``).

    ``comments``: the text of its ``#`` lines, wherever they are, ``#`` and the spaces after it
    taken off (a recording's notes, e.g. the arm it was recorded on:
    :mod:`ftkin.io.recorded_robot`).
    """

    source: str
    header: list[str]
    rows: list[list[str]]
    lines: list[int]
    header_line: int | None = None
    accel_unit: str | None = None
    comments: tuple[str, ...] = ()

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
                    value = float_text(cell)
                except ValueError:
                    raise InvalidSamples(_not_a_number(name, cell), self.source, line) from None
                if not np.isfinite(value):
                    raise InvalidSamples(
                        f"column {name!r}: {cell!r} is not finite; expected a finite number",
                        self.source,
                        line,
                    )
                out[r, c] = value
        return out

    def booleans(self, name: str, meaning: str) -> np.ndarray:
        """The column ``name`` of ``1``/``0`` cells as ``(N,)`` booleans (``meaning``: what they
        stand for, e.g. ``"1 (closed) or 0 (open)"``), or :class:`InvalidSamples` at the first
        other cell, with its line."""
        index = self.column_index(name)
        for row, line in zip(self.rows, self.lines):
            if (cell := row[index].strip()) not in ("0", "1"):
                raise InvalidSamples(
                    f"column {name!r}: {cell!r} is not 1 or 0; expected {meaning}",
                    self.source,
                    line,
                )
        return np.array([row[index].strip() == "1" for row in self.rows], dtype=bool)


def sniff_delimiter(text: str) -> str:
    """The separator of a CSV text: comma, semicolon or tab, judged by its header line.

    The first line that is neither blank nor a ``#`` comment is the header; a
    header with semicolons or tabs and no commas is read with that separator.
    """
    header = next((line for line in io.StringIO(text) if line.strip()[:1] not in ("", "#")), "")
    semicolons, tabs = header.count(";"), header.count("\t")
    if "," not in header and max(semicolons, tabs) > 0:
        return ";" if semicolons >= tabs else "\t"
    return ","


def read_table(path) -> Table:
    """Read a CSV with a header row; ``#`` lines are comments.

    The separator is sniffed from the header (comma, semicolon or tab; a
    semicolon- or tab-separated file is read and a warning names the
    separator). Duplicated header names are found in linear time.

    Raises:
        InvalidSamples: missing or empty file, no data rows, duplicated
            columns, a row with the wrong number of cells (decimal commas are
            named), or a cell the csv module cannot parse (too long, NUL byte).
    """
    source = str(path)
    text = _read_text(Path(path))
    delimiter = sniff_delimiter(text)
    if delimiter != ",":
        logger.warning(
            "%s: read as a %s-separated file (ftkin writes commas)",
            source,
            DELIMITER_NAMES[delimiter],
        )
    header, header_line, rows, lines, comments = None, None, [], [], []
    reader = csv.reader(io.StringIO(text), delimiter=delimiter)
    try:
        for record in reader:
            number = reader.line_num
            if record and record[0].lstrip().startswith("#"):
                comments.append(delimiter.join(record).lstrip().lstrip("#").strip())
                continue
            if not record or not "".join(record).strip():
                continue
            if header is None:
                header, header_line = [cell.strip() for cell in record], number
                duplicates = sorted(name for name, count in Counter(header).items() if count > 1)
                if duplicates:
                    shown = duplicates[:10] + (["..."] if len(duplicates) > 10 else [])
                    raise InvalidSamples(
                        f"duplicated column(s) {shown} in the header", source, number
                    )
                continue
            if len(record) != len(header):
                raise InvalidSamples(_cell_count_message(record, header, delimiter), source, number)
            rows.append(record)
            lines.append(number)
    except csv.Error as error:
        raise InvalidSamples(
            f"cannot parse the CSV: {error} (a cell longer than {csv.field_size_limit()} "
            "characters, a NUL byte "
            "or an unclosed quote?)",
            source,
            reader.line_num,
        ) from None
    if header is None:
        raise InvalidSamples("file is empty; expected a header row and data rows", source)
    if not rows:
        raise InvalidSamples("no data rows after the header", source)
    return Table(source, header, rows, lines, header_line, comments=tuple(comments))


def read_header(path) -> list[str]:
    """The header row of a CSV (its first line neither blank nor a ``#`` comment), read without
    its rows: to decide how to read a file before reading it. A file :func:`read_table` would
    refuse gets :func:`read_table`'s error."""
    try:
        with open(path, encoding="utf-8-sig") as stream:
            for line in stream:
                if line.strip() and not line.lstrip().startswith("#"):
                    record = next(csv.reader([line], delimiter=sniff_delimiter(line)))
                    header = [cell.strip() for cell in record]
                    if len(set(header)) == len(header):
                        return header
                    break  # duplicated names: read_table names them
    except (OSError, UnicodeDecodeError, csv.Error, StopIteration):
        pass
    return read_table(path).header


def _read_text(path: Path) -> str:
    """The text of a CSV file, or :class:`InvalidSamples` (missing, a folder, binary, JSON)."""
    source = str(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark (Excel) is not a header
    except FileNotFoundError:
        raise InvalidSamples("file not found", source) from None
    except IsADirectoryError:
        bag = (path / "metadata.yaml").is_file()
        raise InvalidSamples(
            "is a ROS 2 bag folder; this command reads a samples CSV: write one with 'ftkin "
            "extract BAG -o samples.csv'"
            if bag
            else "is a folder; expected a CSV file (or a ROS 2 bag folder with metadata.yaml)",
            source,
        ) from None
    except UnicodeDecodeError as error:
        line = error.object[: error.start].count(b"\n") + 1
        raise InvalidSamples(
            f"byte 0x{error.object[error.start]:02x} is not UTF-8 text ({error.reason}): save the "
            "file as UTF-8 (Latin-1 and Windows-1252 write µ, ° and ² in other bytes), unless it "
            "is not a CSV at all",
            source,
            line,
        ) from None
    except OSError as error:
        raise InvalidSamples(f"cannot read: {error.strerror or error}", source) from None
    if text.lstrip()[:1] in ("{", "["):
        raise InvalidSamples(
            "this is a JSON file (an ftkin calibration?), not a CSV table; expected a header row "
            "and data rows",
            source,
        )
    return text


def _cell_count_message(record, header, delimiter) -> str:
    message = f"{len(record)} cells but the header has {len(header)} columns"
    if (
        delimiter == ","
        and len(record) > len(header)
        and not any("." in cell for cell in record)  # a file with decimal commas has no points
        and re.search(r"\d,\d", ",".join(record))
        and any(re.fullmatch(r"\d+", cell.strip()) for cell in record[1:])
    ):
        message += (
            "; the numbers look like they have decimal commas (e.g. 1,5): write them with a "
            "decimal point, or separate the cells with semicolons"
        )
    return message


def rename_columns(table: Table, aliases: dict[str, str]) -> Table:
    """A copy of ``table`` with header names replaced by ``aliases`` (``{old: new}``)."""
    return replace(table, header=[aliases.get(name, name) for name in table.header])


def missing_columns(table: Table, wanted, what: str) -> None:
    """Refuse a table without the ``wanted`` columns, naming a column that may be meant."""
    missing = [name for name in wanted if name not in table.header]
    if not missing:
        return
    lowered = {column.lower(): column for column in reversed(table.header)}  # the first one
    hints, flags = [], []
    for name in missing:
        close = lowered.get(name.lower())
        if close is None:  # a column spelled as the name with a suffix: Fz_N, fz (N)
            close = next(
                (c for c in table.header if c.lower().startswith(name.lower()) and c != name), None
            )
        if close is None and len(table.header) <= 1000:
            import difflib  # only for an error message

            close = next(iter(difflib.get_close_matches(name, table.header, n=1)), None)
        if close is not None:
            hints.append(f"rename column {close!r} to {name!r}")
            flags.append(f"--column {name}={close}")
    hint = (
        (" (did you mean: " + "; ".join(hints) + "?); or read it as it is with " + " ".join(flags))
        if hints
        else ""
    )
    shown = table.header if len(table.header) <= 30 else [*table.header[:30], "..."]
    raise InvalidSamples(
        f"missing {what} column(s) {missing}{hint}; the header has {shown}",
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
    writer.writerows(
        [format_float(cell) if isinstance(cell, (float, np.floating)) else cell for cell in row]
        for row in rows
    )
    return atomic_write_text(path, buffer.getvalue())
