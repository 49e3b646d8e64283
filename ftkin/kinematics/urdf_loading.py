"""Load a URDF into Pinocchio and, when it refuses, say why.

Pinocchio's URDF parser raises a generic "does not contain a valid URDF model"
and prints the real reason on the C-level stderr. This module captures that
stream and adds the reasons of an XML parse and of yourdfpy's validation, so
the :class:`~ftkin.exceptions.UrdfError` a user sees names the problem.
"""

import contextlib
import io
import logging
import os
import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput, UrdfError

logger = logging.getLogger(__name__)


@contextlib.contextmanager
def captured_c_stderr():
    """Redirect file descriptor 2 (C/C++ stderr) into a buffer for the block.

    Yields a list that holds the captured text after the block ends.
    """
    captured: list[str] = []
    try:
        saved = os.dup(2)
    except OSError:  # no usable stderr (embedded interpreter): capture nothing
        yield captured
        return
    import tempfile  # imported when an arm is loaded, not with ftkin

    with tempfile.TemporaryFile(mode="w+b") as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield captured
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            captured.append(sink.read().decode(errors="replace"))


def xml_reasons(text: str) -> list[str]:
    """Problems an XML parser finds (empty list when the XML is well formed)."""
    import xml.etree.ElementTree as ET  # imported when an arm is loaded, not with ftkin

    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        line, column = error.position
        return [f"not well-formed XML at line {line}, column {column}: {error}"]
    if root.tag != "robot":
        return [f"root element is <{root.tag}>, expected <robot>"]
    return tree_reasons(root) or joint_reasons(root)


DEGREE_LIMIT = 4.0 * np.pi
"""A revolute joint limit beyond this [rad] (two turns) is taken for degrees: no arm's joint
turns that far, and ±170° written as -170 170 reads as 27 turns."""
MOST_DEGREES = 370.0
"""Limits beyond this are not degrees but "unbounded" written as a huge number (``1e16``, as
some URDFs mark a rotor): taken as they are."""


def joint_reasons(root) -> list[str]:
    """Problems of the joints Pinocchio would take as they are: a moving joint whose axis is
    the zero vector (it would turn about nothing), a revolute joint whose limits look like
    degrees (URDF limits are radians)."""
    reasons = []
    for joint in root.findall("joint"):
        name, kind = joint.get("name"), joint.get("type")
        if kind not in ("revolute", "continuous", "prismatic"):
            continue
        axis = joint.find("axis")
        try:
            direction = [
                float(v)
                for v in (axis.get("xyz", "1 0 0") if axis is not None else "1 0 0").split()
            ]
        except ValueError:
            direction = []
        if (
            len(direction) != 3
            or not np.all(np.isfinite(direction))
            or np.linalg.norm(direction) < 1e-9
        ):
            text = axis.get("xyz") if axis is not None else None
            reasons.append(
                f"joint [{name}] has axis xyz={text!r}: expected a direction of three finite "
                'numbers, not all zero (e.g. "0 0 1")'
            )
        limit = joint.find("limit")
        if kind != "revolute" or limit is None:
            continue
        try:
            bounds = [float(limit.get(end, "0")) for end in ("lower", "upper")]
        except ValueError:
            continue  # Pinocchio names a limit that is not a number
        if DEGREE_LIMIT < max(abs(bound) for bound in bounds) <= MOST_DEGREES:
            reasons.append(
                f"joint [{name}] has limits lower={bounds[0]:g} upper={bounds[1]:g}, beyond "
                f"±{DEGREE_LIMIT:.4g} rad (two turns): URDF limits are in radians (these look "
                f"like degrees: {np.deg2rad(bounds[0]):.4g} {np.deg2rad(bounds[1]):.4g} rad)"
            )
    return reasons


def tree_reasons(root) -> list[str]:
    """Problems of the link/joint tree: a joint naming a missing link, a link with two parent
    joints or a cycle (a kinematic loop: URDF describes trees), no root or several roots.
    """
    links = {link.get("name") for link in root.findall("link")}
    parent_of, reasons = {}, []
    for joint in root.findall("joint"):
        name = joint.get("name")
        ends = {
            end: (joint.find(end).get("link") if joint.find(end) is not None else None)
            for end in ("parent", "child")
        }
        for end, link in ends.items():
            if link is None:
                reasons.append(f'joint [{name}] is missing a {end} link (<{end} link="..."/>)')
            elif link not in links:
                reasons.append(
                    f"joint [{name}] names {end} link {link!r}, which is not a <link> of this URDF"
                )
        child = ends["child"]
        if child in parent_of:
            reasons.append(
                f"link {child!r} is the child of two joints ([{parent_of[child][0]}] and "
                f"[{name}]): a kinematic loop; URDF describes a tree"
            )
        parent_of.setdefault(child, (name, ends["parent"]))
    if reasons:
        return reasons
    for start in parent_of:  # walk up from every child: a cycle never reaches a root
        seen, link = [start], parent_of[start][1]
        while link in parent_of and link not in seen:
            seen.append(link)
            link = parent_of[link][1]
        if link in seen:
            return [
                f"the joints form a cycle through links {seen}: a kinematic loop; URDF "
                "describes a tree"
            ]
    roots = sorted(links - set(parent_of))
    if len(roots) != 1 and links:
        return [
            f"{len(roots)} root links {roots[:10]}; a URDF tree has exactly one (a link no "
            "joint has as its child)"
        ]
    return []


def yourdfpy_reasons(text: str, check_meshes: bool = False) -> list[str]:
    """Per-field problems found by yourdfpy (empty if it is not installed or finds none)."""
    try:
        import yourdfpy
    except ImportError:
        return []
    messages = io.StringIO()
    handler = logging.StreamHandler(messages)
    yourdfpy_logger = logging.getLogger("yourdfpy")
    yourdfpy_logger.addHandler(handler)
    try:
        robot = yourdfpy.URDF.load(
            io.BytesIO(text.encode()), build_scene_graph=False, load_meshes=False
        )
        if all([robot.validate(), robot.validate_filenames() if check_meshes else True]):
            return []
    except Exception as error:  # yourdfpy raises many types on bad input
        return [f"yourdfpy: {error}"]
    finally:
        yourdfpy_logger.removeHandler(handler)
    return [line.strip() for line in messages.getvalue().splitlines() if line.strip()]


_XML_COMMENT = re.compile(r"<!--.*?-->", re.DOTALL)
_XACRO_MARK = re.compile(r"<xacro:|\$\{|\$\(")  # macros, properties, substitution args


def read_urdf_text(path: Path) -> str:
    """Read a URDF file or raise :class:`UrdfError` (missing, unreadable, not text)."""
    if path.is_dir():
        inside = sorted(p.name for p in path.glob("*.urdf"))[:5]
        raise UrdfError(
            str(path),
            [f"is a folder, expected a URDF file{f' (it holds {inside})' if inside else ''}"],
        )
    if not path.is_file():
        raise UrdfError(str(path), ["file not found"])
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as error:
        raise UrdfError(str(path), [f"cannot read file: {error}"]) from None
    if path.name.endswith(".xacro") or _XACRO_MARK.search(_XML_COMMENT.sub("", text)):
        raise UrdfError(
            str(path),
            [
                f"this is a xacro file, not a URDF: run xacro first (xacro {path.name} > "
                "robot.urdf) and give the result"
            ],
        )
    return text


_SOURCE_LOCATION = re.compile(r"^at line \d+ in \S+\.(cpp|hpp|h|cc)$")


def _parser_lines(stderr: list[str]) -> list[str]:
    """The parser's messages without its source-code locations ("at line 262 in model.cpp"),
    which read like lines of the user's URDF."""
    lines = (" ".join(line.split()) for line in "".join(stderr).splitlines())
    return [line for line in lines if line and not _SOURCE_LOCATION.match(line)]


def build_model(path: Path) -> pin.Model:
    """Build the kinematic model of a URDF file with Pinocchio.

    Raises:
        UrdfError: with the reasons from the XML parser, yourdfpy's validation
            and Pinocchio's own stderr.
    """
    text = read_urdf_text(path)
    reasons = xml_reasons(text)
    if reasons:
        raise UrdfError(str(path), reasons)
    with captured_c_stderr() as stderr:
        try:
            return pin.buildModelFromUrdf(str(path))
        except (RuntimeError, ValueError) as caught:
            error = caught
    reasons = [f"Pinocchio: {line}" for line in _parser_lines(stderr)] + yourdfpy_reasons(text)
    raise UrdfError(str(path), reasons or [f"Pinocchio: {error}"]) from None


_MESH_ELEMENT = re.compile(r"(<mesh\b[^>]*?\bfilename\s*=\s*)([\"'])(.*?)\2", re.DOTALL)
_PACKAGE_URI = re.compile(r"^package://([^/]+)/(.*)$")


def _package_name(folder: Path) -> str | None:
    """The ``<name>`` of ``folder/package.xml`` (a ROS package), or None."""
    manifest = folder / "package.xml"
    if not manifest.is_file():
        return None
    match = re.search(r"<name>\s*([^<\s]+)\s*</name>", manifest.read_text(errors="replace"))
    return match.group(1) if match else None


def mesh_candidates(uri: str, urdf_path: Path, package_dirs) -> list[Path]:
    """Where a mesh URI of the URDF at ``urdf_path`` may be, in the order they are tried.

    * an absolute path, or ``file://`` + absolute path: itself;
    * a relative path: relative to the URDF's own folder (how ROS tools and MuJoCo read it);
    * ``package://NAME/REST``: ``DIR/NAME/REST`` for each of ``package_dirs``, then a package
      beside or above the URDF: a folder on the URDF's path named ``NAME`` or holding a
      ``package.xml`` whose ``<name>`` is ``NAME`` (``ANCESTOR/REST``), or a folder ``NAME``
      inside one of the URDF's ancestors (``ANCESTOR/NAME/REST``).
    """
    text = uri.strip()
    if text.startswith("file://"):
        text = text[len("file://") :]
    package = _PACKAGE_URI.match(text)
    if package is None:
        given = Path(text)
        return [given] if given.is_absolute() else [urdf_path.parent / given]
    name, rest = package.groups()
    candidates = [Path(folder) / name / rest for folder in package_dirs]
    for ancestor in urdf_path.resolve().parents:
        if ancestor.name == name or _package_name(ancestor) == name:
            candidates.append(ancestor / rest)
        candidates.append(ancestor / name / rest)
    return candidates


def resolve_mesh_paths(text: str, urdf_path: Path, package_dirs=()) -> tuple[str, list[str]]:
    """The URDF text with every mesh filename made an absolute path that exists, and the
    URIs that resolve nowhere (see :func:`mesh_candidates`; each named once).
    """
    missing: list[str] = []

    def replace(match: re.Match) -> str:
        uri = match.group(3)
        found = next(
            (path for path in mesh_candidates(uri, urdf_path, package_dirs) if path.is_file()),
            None,
        )
        if found is None:
            if uri not in missing:
                missing.append(uri)
            return match.group(0)
        quote = match.group(2)
        return f"{match.group(1)}{quote}{found.resolve().as_posix()}{quote}"

    return _MESH_ELEMENT.sub(replace, text), missing


def build_geometry(
    model: pin.Model, path: Path, kind: str, package_dirs: list[str]
) -> pin.GeometryModel:
    """Collision or visual geometry of a URDF (meshes resolved by :func:`resolve_mesh_paths`).

    Raises:
        UrdfError: a mesh that resolves nowhere (named once, with where it was looked for and
            the fix), or Pinocchio refuses the geometry.
    """
    geometry_type = {"collision": pin.GeometryType.COLLISION, "visual": pin.GeometryType.VISUAL}[
        kind
    ]
    text, missing = resolve_mesh_paths(read_urdf_text(path), path, package_dirs)
    if missing:
        more = f" and {len(missing) - 3} more" if len(missing) > 3 else ""
        shown = ", ".join(missing[:3]) + more
        raise UrdfError(
            str(path),
            [
                f"{len(missing)} {kind} mesh(es) not found: {shown} (looked beside the URDF, in "
                "its parent folders for the package, and in the package folders given); give "
                "--package-dir DIR (Python: package_dirs=[DIR]), the folder that holds the "
                "package, or copy the meshes beside the URDF"
            ],
        )
    with captured_c_stderr() as stderr:
        try:
            return pin.buildGeomFromUrdfString(
                model, text, geometry_type, package_dirs=list(package_dirs)
            )
        except (RuntimeError, ValueError, OSError) as caught:
            error = caught
    raise UrdfError(str(path), [f"Pinocchio: {error}", *_parser_lines(stderr)]) from None


def sensor_frame_hint(model: pin.Model) -> str:
    """How to add a sensor frame the URDF lacks, naming its last link.

    The last link: the last body frame on the last joint (e.g. ``tool0``, ``wrist_3_link``).
    """
    bodies = [frame.name for frame in model.frames if frame.parentJoint == model.njoints - 1]
    last = bodies[-1] if bodies else model.frames[len(model.frames) - 1].name
    return (
        "if the URDF has no sensor frame, add it at the link the sensor is bolted to, e.g. "
        f"--sensor-parent {last} "
        f"(and --sensor-offset X Y Z [m]; in Python sensor_mount=SensorMount({last!r}, ...))"
    )


def joints_beyond_frame(model: pin.Model, frame: str) -> dict[str, float]:
    """``{joint name: value}`` for the joints that do not move ``frame`` (a gripper's fingers).

    The value is the joint's neutral position clipped to its limits [rad or m]. Empty when the
    frame is not in the model (the caller reports that) or every joint moves it.
    """
    if not model.existFrame(frame):
        return {}
    support = set(model.supports[model.frames[model.getFrameId(frame)].parentJoint])
    neutral = np.clip(pin.neutral(model), model.lowerPositionLimit, model.upperPositionLimit)
    return {
        model.names[joint_id]: float(neutral[joint.idx_q])
        for joint_id, joint in enumerate(model.joints)
        if joint_id > 0 and joint_id not in support and joint.nq == 1
    }


def lock_joints(model: pin.Model, locked_joints: Mapping[str, float]):
    """The model with ``{joint name: value [rad or m]}`` fixed: ``(reduced, full, locked ids,
    reference q)``.

    Raises:
        InvalidInput: a joint name is not in the model (lists the joints).
    """
    reference = pin.neutral(model)
    ids = []
    for name, value in locked_joints.items():
        if not model.existJointName(name):
            raise InvalidInput(
                f"cannot lock joint {name!r}: not in the model; joints: "
                + ", ".join(model.names[i] for i in range(1, model.njoints))
            )
        joint_id = model.getJointId(name)
        reference[model.joints[joint_id].idx_q] = float(value)
        ids.append(joint_id)
    return pin.buildReducedModel(model, ids, reference), model, ids, reference
