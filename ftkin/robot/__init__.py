"""ftkin on a real robot: the calibration session, the payload hand-off and the control loop.

* :class:`Robot` and :class:`ForceTorqueSensor`: what ftkin needs from a robot and a sensor;
* :class:`FrankaRobot`: a Franka FR3 or Panda through franky-control (extra ``franka``);
* :func:`calibrate_on_robot`: plan, visit, wait for stillness, record, calibrate, save, verify;
* :func:`record_poses`: the same from an arm ftkin does not drive (a :class:`JointStateSource`
  read while someone else moves it), ``ftkin record``;
* :func:`run_admittance`: the paced loop read state → :class:`~ftkin.JointAdmittance` → joint
  velocities, stopping cleanly on any fault; :func:`hand_guiding` its hand-guiding preset;
* :class:`UrArm`: a Universal Robots arm read through ur_rtde (extra ``ur``): joints, flange
  pose and the built-in wrist sensor (:class:`UrWristSensor`); :func:`compensated_stream`: the
  compensated samples of any joint reader and sensor, for a user's own loop;
* :class:`LoadHandoff`: the tool and the load a tracker identified in the hand, kept up to date in
  the robot's controller (:meth:`FrankaRobot.set_load_from` once);
* :class:`FrankaSim`: a franky-sim FR3 with a wrist sensor, a tool and pushes, for tests and
  the demo.

Names load their module on first use; franky and ur_rtde are imported only when a robot is
created.
"""

from .._lazy import lazy_exports

_EXPORTS = {
    "CheckedSensor": ".stillness",
    "ForceTorqueSensor": ".protocols",
    "FrankaRobot": ".franka",
    "FrankaSim": ".franka_sim",
    "JointStateSource": ".protocols",
    "LoadHandoff": ".load_handoff",
    "LoopStats": ".loop",
    "Robot": ".protocols",
    "SamplesLog": ".samples_log",
    "SimHeld": ".franka_sim",
    "SimSensorSpec": ".franka_sim",
    "SimTool": ".franka_sim",
    "Stillness": ".stillness",
    "UrArm": ".ur",
    "UrWristSensor": ".ur",
    "Verification": ".session",
    "calibrate_on_robot": ".session",
    "compensated_stream": ".live_compensation",
    "hand_guiding": ".guiding",
    "held_load_of": ".load_handoff",
    "load_sensor_factory": ".sensor_factory",
    "record_poses": ".recorder",
    "run_admittance": ".loop",
    "verify_on_robot": ".session",
    "verify_session": ".session",
    "wait_still": ".stillness",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
