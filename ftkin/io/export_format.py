"""One interface for every export format: ROS controller parameters and robot payloads alike.

An :class:`ExportFormat` has a ``name`` (the ``--format`` choice), a one-line ``summary``,
whether it ``needs_arm`` (a payload moves the centre of mass to the flange through the URDF), its
own :class:`ExportOption` s (``--frame-id``, ``--flange-frame``, ...) and three methods over one
:class:`ExportRequest`: :meth:`~ExportFormat.document` (what is written, as nested dicts),
:meth:`~ExportFormat.notes` (what the format cannot hold, written as comments and printed) and
:meth:`~ExportFormat.text` (the file's text; YAML with comments unless overridden).
:mod:`ftkin.io.export` holds the registry and the entry points.
"""

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from ..validation import as_ros_name
from .yaml_text import yaml_text


@dataclass(frozen=True)
class ExportOption:
    """An option of one or more formats: a keyword of the Python call and a command-line flag.

    Attributes:
        name: Keyword in :attr:`ExportRequest.options` (and the argparse ``dest``).
        flag: Command-line flag, e.g. ``--frame-id``.
        help: Help text.
        argparse: Further ``add_argument`` settings (``metavar``, ``type``, ``nargs``,
            ``action``); the default is always None (not given).
        ros_name: ``"node"``, ``"frame"`` or ``"topic"``: the value is written into the file as
            such a ROS name and is checked against ROS's rules
            (:func:`ftkin.validation.as_ros_name`) before anything is written.
    """

    name: str
    flag: str
    help: str
    argparse: Mapping[str, Any] = field(default_factory=dict)
    ros_name: str | None = None

    def check(self, value):
        """``value`` as the format receives it (a ROS name checked), or InvalidInput."""
        if value is None or self.ros_name is None:
            return value
        return as_ros_name(value, self.ros_name, self.flag)


@dataclass(frozen=True)
class ExportRequest:
    """What one export is made of.

    Attributes:
        calibration: The calibration (:class:`~ftkin.calibration.model.SensorModel` or a result).
        arm: The arm as its URDF describes it (formats that need one), else None.
        options: The format's options that were given, by :attr:`ExportOption.name`.
        path: The output file, when writing one (a format may choose its form by the suffix).
    """

    calibration: Any
    arm: Any = None
    options: Mapping[str, Any] = field(default_factory=dict)
    path: Path | None = None

    def option(self, name: str, default=None):
        """The option ``name`` if given, else ``default``."""
        value = self.options.get(name)
        return default if value is None else value


class ExportFormat(ABC):
    """An export format; subclass, set the class attributes, implement :meth:`document`.

    Register an instance with :func:`ftkin.io.export.register_export_format`.

    Attributes:
        name: The ``--format`` choice.
        summary: One line for ``ftkin export --help``: the target and what is written.
        needs_arm: True when the format needs the arm (the CLI then builds it from the robot
            options).
        options: The format's own options.
    """

    name: ClassVar[str]
    summary: ClassVar[str]
    needs_arm: ClassVar[bool] = False
    options: ClassVar[tuple[ExportOption, ...]] = ()

    @abstractmethod
    def document(self, request: ExportRequest) -> dict:
        """What the file holds, as nested dicts of plain values (SI units)."""

    def notes(self, request: ExportRequest) -> list[str]:
        """What the format cannot hold about the calibration, one sentence each."""
        return []

    def header(self, request: ExportRequest) -> list[str]:
        """Comment lines above the document (the notes follow them)."""
        return [f"ftkin calibration exported for {self.name}"]

    def summary_line(self, request: ExportRequest) -> str:
        """What the CLI prints after ``wrote FORMAT to PATH`` (e.g. the payload's mass)."""
        return ""

    def text(self, request: ExportRequest) -> str:
        """The file's text: :meth:`document` as YAML under the header and the notes."""
        document = self.document(request)  # first: its errors say what is wrong with the input
        comments = [*self.header(request), *(f"NOTE: {note}" for note in self.notes(request))]
        return yaml_text(document, comments)
