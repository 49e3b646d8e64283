"""ftkin's own RTDE reader (every package, in order) against the RTDE controller emulator, which
was written from UR's protocol guide and records what it sent; and the package log built on it.
No ur_rtde here: the reader speaks the protocol itself."""

from __future__ import annotations

import time

import numpy as np
import pytest

from ftkin.exceptions import InvalidInput, RobotConnectionLost
from ftkin.robot.rtde_packages import RtdePackages

from .rtde_controller import EmulatedController, SimulatedTool, flange_transform


@pytest.fixture
def controller():
    try:
        emulated = EmulatedController()
    except OSError as error:
        pytest.skip(f"cannot serve RTDE on a loopback address, port 30004: {error}")
    yield emulated
    emulated.kill()


def test_a_late_reader_misses_no_package(controller):
    with RtdePackages(controller.host) as packages:
        batches = []
        for index in range(400):
            batches.append(packages.read())
            if index % 50 == 49:
                time.sleep(0.08)  # a reader 40 packages late, eight times
    stamps = np.concatenate([batch.timestamps for batch in batches])
    sent = np.array(sorted(stamp for stamp, _ in controller.sent()))
    sent = sent[(sent >= stamps[0]) & (sent <= stamps[-1])]
    np.testing.assert_allclose(stamps, sent, rtol=0, atol=1e-9)  # every one, once, in order
    assert max(len(batch) for batch in batches) >= 20  # the late reads took the queue at once
    last = batches[-1]
    state = controller.state()  # the package's fields as the emulator computed them
    assert last.joint_positions.shape == (len(last), 6) and last.wrenches.shape == (len(last), 6)
    np.testing.assert_allclose(last.joint_positions[-1], state["q"], atol=1e-12)


def test_the_wrench_is_the_emulators_in_base_axes(controller):
    q = [0.3, -1.2, 1.0, -1.4, -1.5, 0.6]
    controller.set_pose(q)
    controller.set_tool(force_noise=0.0, torque_noise=0.0)
    time.sleep(0.05)
    with RtdePackages(controller.host) as packages:
        batch = packages.read()
    rotation = flange_transform("ur5e", q)[:3, :3]
    in_sensor = SimulatedTool(force_noise=0.0, torque_noise=0.0).wrench_in_sensor(rotation)
    expected = np.concatenate([rotation @ in_sensor[:3], rotation @ in_sensor[3:]])
    np.testing.assert_allclose(batch.wrenches[-1], expected, atol=1e-9)


def test_a_frozen_and_a_killed_controller_are_lost_connections(controller):
    with RtdePackages(controller.host, timeout=0.3) as packages:
        packages.read()
        controller.freeze()
        started = time.monotonic()
        with pytest.raises(RobotConnectionLost, match="no RTDE data .* for 0.3 s"):
            while True:
                packages.read()
        assert time.monotonic() - started < 1.0
    controller.freeze(False)
    with RtdePackages(controller.host) as packages:
        packages.read()
        controller.kill()
        with pytest.raises(RobotConnectionLost, match="closed RTDE|failed"):
            while True:
                packages.read()


def test_bad_arguments_and_nothing_listening():
    with pytest.raises(InvalidInput, match="host"):
        RtdePackages("")
    with pytest.raises(InvalidInput, match="frequency"):
        RtdePackages("127.0.0.1", frequency=1000)
    with pytest.raises(InvalidInput, match="timeout"):
        RtdePackages("127.0.0.1", timeout=0)
    with pytest.raises(RobotConnectionLost, match="cannot read RTDE from 127.3.2.1"):
        RtdePackages("127.3.2.1", timeout=0.5)
