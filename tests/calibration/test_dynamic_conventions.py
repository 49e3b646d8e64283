"""A moving recording whose readings are the reaction: the convention is named, not "is there a
tool?".
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.calibration.dynamic import calibrate_dynamic
from ftkin.calibration.regressor import MotionSamples
from ftkin.exceptions import SuspectConvention
from ftkin.planning.constraints import PoseConstraints
from ftkin.planning.excitation import plan_excitation
from ftkin.sim.mujoco.tool_inertia import ToolInertia

pytest.importorskip("mujoco")


def test_negated_motion_readings_name_the_sign(arm):
    from ftkin.sim.mujoco.recording import MujocoRecorder

    tool = ToolInertia(1.5, [0.006, -0.012, 0.072], np.diag([0.006, 0.005, 0.002]))
    recorder = MujocoRecorder(
        joint_names=arm.joint_names, tool=tool
    )  # MuJoCo: independent of ftkin's regressor
    plan = plan_excitation(
        arm,
        6.0,
        rate=100.0,
        period=3.0,
        constraints=PoseConstraints(floor_height=0.15),
        seed=0,
        candidates=5,
        optimize=False,
    )
    wrenches = recorder.wrenches(
        plan.joint_positions, plan.joint_velocities, plan.joint_accelerations
    )
    motion = MotionSamples.from_joint_trajectory(
        arm,
        plan.joint_positions,
        plan.joint_velocities,
        plan.joint_accelerations,
        -wrenches,
        plan.times,
    )
    with pytest.raises(
        SuspectConvention, match="reaction.*dynamic calibration takes none of these options"
    ) as caught:
        calibrate_dynamic(motion)
    assert caught.value.sensor_sign == -1
    assert calibrate_dynamic(
        MotionSamples.from_joint_trajectory(
            arm,
            plan.joint_positions,
            plan.joint_velocities,
            plan.joint_accelerations,
            wrenches,
            plan.times,
        )
    ).tool_mass == pytest.approx(1.5, rel=1e-3)
