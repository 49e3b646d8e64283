"""ftkin.viz without a browser: arrow geometry, the transforms sent to meshcat, server lifecycle,
CLI.
"""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest

from ftkin import Arm, MissingDependency, SensorModel, calibrate, save_calibration
from ftkin.calibration.information import SensorNoise
from ftkin.cli import main
from ftkin.exceptions import InvalidInput
from ftkin.io.csv_table import write_csv
from ftkin.sim.sensor import SimulatedSensor
from ftkin.viz import ArrowStyle, arrow_placement, exaggerate_tilt, pose_vectors, rotation_y_to
from ftkin.viz.server import import_meshcat

pytest.importorskip("meshcat")

from ftkin.viz import CalibrationViewer  # noqa: E402

Q_SIDE = np.array([0.3, 0.2, -0.3, 0.0, 0.2, 0.0])  # rad: tool roughly horizontal


def _point(matrix: np.ndarray, local) -> np.ndarray:
    return (matrix @ np.append(np.asarray(local, dtype=float), 1.0))[:3]


def _axis_angle_deg(a, b) -> float:
    return float(np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b))))


class Recorder:
    """A stand-in for meshcat.Visualizer that records what is sent, per path."""

    def __init__(self, store=None, path=None):
        from meshcat.path import Path

        self.store = store if store is not None else {"transform": {}, "object": {}, "property": {}}
        self.path = path if path is not None else Path()

    def __getitem__(self, path):
        return Recorder(self.store, self.path.append(path))

    @property
    def key(self) -> str:
        return self.path.lower()

    def set_object(self, geometry, material=None):
        self.store["object"][self.key] = (geometry, material)

    def set_transform(self, matrix):
        self.store["transform"][self.key] = np.array(matrix)

    def set_property(self, key, value):
        self.store["property"][(self.key, key)] = value

    def get_image(self):  # Pinocchio checks that it exists
        raise NotImplementedError

    def url(self):
        return "http://recorder/"


# ------------------------------------------------------------------ arrows
@pytest.mark.parametrize(
    "direction",
    [
        (0, 1, 0),
        (0, -1, 0),
        (1, 0, 0),
        (-1, 0, 0),
        (0, 0, 1),
        (0, 0, -1),
        (0.3, -0.2, 0.9),
        (1, 1e-9, 0),
    ],
)
def test_rotation_y_to_is_a_rotation_with_y_along_direction(direction):
    rotation = rotation_y_to(direction)
    unit = np.asarray(direction, float) / np.linalg.norm(direction)
    np.testing.assert_allclose(rotation.T @ rotation, np.eye(3), atol=1e-12)
    assert np.linalg.det(rotation) == pytest.approx(1.0)
    np.testing.assert_allclose(rotation @ [0.0, 1.0, 0.0], unit, atol=1e-12)


def test_arrow_tip_base_and_length_match_vector_times_scale(rng):
    style = ArrowStyle(shaft_radius=0.01, head_radius=0.02, head_length=0.05)
    for _ in range(50):
        origin = rng.normal(size=3)
        vector = rng.normal(size=3) * rng.uniform(0.1, 20.0)
        scale = rng.uniform(0.005, 0.2)
        arrow = arrow_placement(origin, vector, scale, style)
        expected_tip = origin + vector * scale
        head, shaft = arrow.head.matrix(), arrow.shaft.matrix()
        # The unit shaft spans local y in [-0.5, 0.5]; the cone spans [-h/2, h/2] with its tip at
        # +h/2.
        np.testing.assert_allclose(_point(shaft, [0, -0.5, 0]), origin, atol=1e-12)
        np.testing.assert_allclose(
            _point(head, [0, style.head_length / 2, 0]), expected_tip, atol=1e-12
        )
        np.testing.assert_allclose(
            _point(shaft, [0, 0.5, 0]), _point(head, [0, -style.head_length / 2, 0]), atol=1e-12
        )
        assert arrow.length == pytest.approx(np.linalg.norm(vector) * scale)
        assert _axis_angle_deg(shaft[:3, 1], vector) < 1e-6
        # The shaft keeps its radius: local x and z stay unit length.
        assert np.linalg.norm(shaft[:3, 0]) == pytest.approx(1.0)
        assert np.linalg.norm(shaft[:3, 2]) == pytest.approx(1.0)


def test_short_and_zero_arrows_shrink_the_head_and_stay_finite():
    style = ArrowStyle(head_length=0.05)
    short = arrow_placement(np.zeros(3), [0.0, 0.0, 0.02], 1.0, style)
    np.testing.assert_allclose(
        _point(short.head.matrix(), [0, style.head_length / 2, 0]), [0, 0, 0.02], atol=1e-12
    )
    assert short.head.scale[0] == pytest.approx(0.01 / 0.05)  # head is half the arrow
    zero = arrow_placement(np.ones(3), np.zeros(3), 0.1, style)
    assert zero.length == 0.0
    assert np.all(np.isfinite(zero.shaft.matrix())) and np.all(np.isfinite(zero.head.matrix()))
    with pytest.raises(InvalidInput, match="arrow scale"):
        arrow_placement(np.zeros(3), np.ones(3), -1.0)


def test_exaggerate_tilt_multiplies_the_angle_and_keeps_the_azimuth(rng):
    for _ in range(20):
        tilt = rng.uniform(1e-4, 0.02)
        azimuth = rng.uniform(-np.pi, np.pi)
        direction = np.array(
            [np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth), -np.cos(tilt)]
        )
        for factor in (1.0, 5.0, 40.0):
            drawn = exaggerate_tilt(3.0 * direction, factor)
            assert np.linalg.norm(drawn) == pytest.approx(1.0)
            assert _axis_angle_deg(drawn, [0, 0, -1]) == pytest.approx(
                np.degrees(tilt * factor), rel=1e-9
            )
            assert np.arctan2(drawn[1], drawn[0]) == pytest.approx(azimuth, abs=1e-9)
    np.testing.assert_allclose(exaggerate_tilt([0, 0, -2.0], 50.0), [0, 0, -1.0])


# ------------------------------------------------------------ pose vectors
def test_pose_vectors_measured_minus_gravity_is_the_contact(arm, truth, rng):
    rotation, origin = arm.frame_placement(Q_SIDE, "sensor")
    contact_in_sensor = np.array([1.0, -2.0, 0.5, 0.1, 0.0, -0.05])
    raw = truth.predict(rotation) + contact_in_sensor
    vectors = pose_vectors(truth, rotation, origin, raw)
    np.testing.assert_allclose(vectors.gravity_force, truth.gravity_in_base)
    np.testing.assert_allclose(vectors.contact_wrench, contact_in_sensor, atol=1e-12)
    np.testing.assert_allclose(vectors.contact_force, rotation @ contact_in_sensor[:3], atol=1e-12)
    np.testing.assert_allclose(
        vectors.measured_force - vectors.gravity_force, vectors.contact_force, atol=1e-12
    )
    np.testing.assert_allclose(vectors.center_of_mass, origin + rotation @ truth.center_of_mass)


# --------------------------------------------------- transforms sent (no server)
def test_show_pose_sends_arrows_equal_to_force_times_scale(arm, truth):
    recorder = Recorder()
    viewer = CalibrationViewer(truth, arm, visualizer=recorder, scale=0.04)
    rotation = arm.rotation_sensor_to_base(Q_SIDE)
    _, origin = arm.frame_placement(Q_SIDE, "sensor")
    contact = np.array([2.0, 0.0, -1.0, 0.0, 0.0, 0.0])
    raw = truth.predict(rotation) + contact
    viewer.show_pose(Q_SIDE, raw)
    sent = recorder.store["transform"]
    head_length = viewer.style.head_length
    expected = {
        "measured": rotation @ (raw[:3] - truth.force_offset),
        "gravity": truth.gravity_in_base,
        "contact": rotation @ contact[:3],
    }
    for name, force in expected.items():
        head = sent[f"/ftkin/{name}/head"]
        shaft = sent[f"/ftkin/{name}/shaft"]
        np.testing.assert_allclose(_point(shaft, [0, -0.5, 0]), origin, atol=1e-9)
        np.testing.assert_allclose(
            _point(head, [0, head_length / 2, 0]), origin + 0.04 * force, atol=1e-9
        )
    np.testing.assert_allclose(sent["/ftkin/sensor"][:3, :3], rotation, atol=1e-12)
    np.testing.assert_allclose(
        sent["/ftkin/center_of_mass"][:3, 3], origin + rotation @ truth.center_of_mass
    )
    # The arm went through Pinocchio's visualizer into the same viewer.
    assert any(path.startswith("/pinocchio/visuals/") for path in sent)
    viewer.close()  # not our server: nothing to stop


def test_tilt_arrow_shows_the_exaggerated_tilt(truth):
    recorder = Recorder()
    viewer = CalibrationViewer(truth, None, visualizer=recorder, tilt_exaggeration=30.0)
    viewer.show_rotation(np.eye(3), truth.predict(np.eye(3)))
    shaft = recorder.store["transform"]["/ftkin/base_gravity/shaft"]
    true_tilt = _axis_angle_deg(truth.gravity_in_base, [0, 0, -1])
    assert _axis_angle_deg(shaft[:3, 1], [0, 0, -1]) == pytest.approx(30.0 * true_tilt, rel=1e-6)
    assert "U=" in viewer.legend() and "×30" in viewer.legend()


def test_animation_tracks_hold_each_pose_and_scale_the_shaft(arm, truth):
    recorder = Recorder()
    viewer = CalibrationViewer(truth, arm, visualizer=recorder, scale=0.05)
    recorder.set_animation = lambda animation, play=True, repetitions=1: recorder.store.setdefault(
        "animation", animation
    )
    q = np.array([Q_SIDE, Q_SIDE + 0.2, Q_SIDE - 0.2])
    raw = truth.predict(arm.rotation_sensor_to_base(q))
    vectors = viewer.animate(raw, configurations=q, hold=0.5, fps=20)
    assert len(vectors) == 3
    animation = recorder.store["animation"]
    clips = {"/".join(path.entries): clip for path, clip in animation.clips.items()}
    track = clips["ftkin/measured/shaft"].tracks["scale"]
    assert track.frames == [0, 9, 10, 19, 20, 29]  # each pose held 0.5 s at 20 frames/s
    head_length = viewer.style.head_length
    lengths = [0.05 * np.linalg.norm(v.measured_force) - head_length for v in vectors]
    np.testing.assert_allclose([value[1] for value in track.values[::2]], lengths)
    assert any(name.startswith("pinocchio/visuals") for name in clips)
    with pytest.raises(InvalidInput, match="exactly one"):
        viewer.animate(raw, hold=0.5)


# --------------------------------------------------------- missing meshcat
def test_missing_meshcat_names_the_extra(monkeypatch, truth, tmp_path):
    monkeypatch.setitem(sys.modules, "meshcat", None)
    with pytest.raises(MissingDependency, match=r"meshcat.*pip install -e '.*\[viz\]'"):
        import_meshcat()
    with pytest.raises(MissingDependency, match="viz"):
        CalibrationViewer(truth)


def test_cli_reports_missing_meshcat(monkeypatch, capsys, calibration_files):
    calib, samples, _ = calibration_files
    monkeypatch.setitem(sys.modules, "meshcat", None)
    assert main(["view", str(calib), str(samples), "--no-wait"]) == 2
    assert "ftkin[viz]" in capsys.readouterr().err


# -------------------------------------------------------- real server
@pytest.fixture(scope="module")
def calibration_files(tmp_path_factory):
    """A calibration from simulated samples on the bundled arm, its samples CSV and a replay log."""
    folder = tmp_path_factory.mktemp("view")
    rng = np.random.default_rng(3)
    arm = Arm.default()
    truth = SensorModel.from_tool(
        0.32,
        [0.002, -0.001, 0.047],
        [0.4, -0.3, 0.2],
        [0.01, 0.02, -0.01],
        base_tilt=(0.003, -0.002),
    )
    sensor = SimulatedSensor(truth, SensorNoise.paper())
    q = np.vstack([Q_SIDE, arm.random_configurations(7, rng, margin=0.3)])
    samples = sensor.samples_at_configurations(arm, q, rng, readings_per_pose=5)
    save_calibration(calibrate(samples), folder / "calib.json")
    header = [f"q{i + 1}" for i in range(arm.nq)] + ["fx", "fy", "fz", "mx", "my", "mz", "pose"]
    rows = [
        [*map(float, qq), *map(float, w), int(p)]
        for qq, w, p in zip(samples.joint_positions, samples.wrenches, samples.pose_ids)
    ]
    write_csv(folder / "samples.csv", header, rows)
    t = np.arange(60) * 0.05
    q_log = Q_SIDE + 0.3 * np.sin(t)[:, None]
    raw_log = sensor.read(arm.rotation_sensor_to_base(q_log), rng)
    write_csv(
        folder / "log.csv",
        ["t", *header[:-1]],
        [[float(a), *map(float, b), *map(float, c)] for a, b, c in zip(t, q_log, raw_log)],
    )
    return folder / "calib.json", folder / "samples.csv", folder / "log.csv"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_close_stops_the_server_process_and_attached_viewers_leave_it(truth, tmp_path):
    with CalibrationViewer(truth) as owner:
        process = owner.server_process
        assert process is not None and process.poll() is None
        attached = CalibrationViewer(truth, zmq_url=owner.visualizer.window.zmq_url)
        assert attached.server_process is None
        attached.show_rotation(np.eye(3), truth.predict(np.eye(3)))
        attached.close()
        assert process.poll() is None  # the owner's server is still there
        page = owner.save_html(tmp_path / "scene.html", caption="unit test")
        text = page.read_text()
        assert "ftkin-legend" in text and "unit test" in text and "1 N = " in text
    assert process.poll() is not None
    assert not _alive(process.pid)  # killed and reaped, no zombie
    owner.close()  # idempotent


def test_cli_view_writes_animated_html_and_replay(calibration_files, tmp_path, capsys):
    calib, samples, log = calibration_files
    out = tmp_path / "poses.html"
    assert main(["view", str(calib), str(samples), "--html", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "8 poses, animated" in out.read_text() and "pose 7" in printed
    # At the calibration poses the measured force lies on the predicted gravity (angle column
    # small).
    angles = [
        float(line.split()[4]) for line in printed.splitlines() if line.strip().startswith("pose ")
    ]
    assert len(angles) == 8 and max(angles) < 1.0
    replay = tmp_path / "replay.html"
    assert (
        main(
            ["view", str(calib), "--replay", str(log), "--html", str(replay), "--max-frames", "20"]
        )
        == 0
    )
    assert "row 59" in capsys.readouterr().out and replay.stat().st_size > 10_000
    assert main(["view", str(calib), str(samples), "--pose", "0", "--no-wait"]) == 0


def test_cli_view_errors(calibration_files, capsys):
    calib, samples, log = calibration_files
    assert main(["view", str(calib), str(samples), "--replay", str(log), "--no-wait"]) == 2
    assert "exactly one" in capsys.readouterr().err
    assert main(["view", str(calib), str(samples), "--pose", "99", "--no-wait"]) == 2
    assert "no pose 99; available: pose 0" in capsys.readouterr().err


def test_drawing_options_or_their_fields(truth):
    """The viewer's drawing settings are one object; the keywords are its shortcut."""
    from ftkin.viz.viewer import DrawingOptions

    options = DrawingOptions(scale=0.04, tilt_exaggeration=3.0, auto_camera=False)
    assert options.scale == 0.04 and options.tilt_exaggeration == 3.0
    with pytest.raises(InvalidInput, match="tilt_exaggeration must be a finite positive number"):
        DrawingOptions(tilt_exaggeration=0.0)
    with pytest.raises(InvalidInput, match="CalibrationViewer takes no colour; expected: scale"):
        CalibrationViewer(truth, colour="red")
    with pytest.raises(InvalidInput, match="not both"):
        CalibrationViewer(truth, drawing=options, scale=0.1)
