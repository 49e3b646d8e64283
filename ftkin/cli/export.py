"""``ftkin export CALIB.json --format FORMAT -o OUT.yaml``: parameters for ROS controllers and robot
payloads.
"""

from __future__ import annotations

from ..io.calibration_file import load_calibration
from ..io.export import EXPORT_FORMATS, export_calibration, export_notes
from ..io.payload_export import PAYLOAD_FORMATS, controller_payload, export_payload
from ..io.payload_inertia import RigidBody
from ..kinematics.arm import Arm
from .common import add_arm_arguments, arm_for_calibration


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "export",
        help="write a calibration as ROS controller parameters or as the robot's payload (Franka, "
        "UR)",
        description="Export a calibration file to: 'admittance' (ros2_controllers "
        "admittance_controller "
        "gravity_compensation.*), 'gravity-compensation' (control_toolbox "
        "GravityCompensationWrench filter "
        "tool.CoG/mass/gravity_field, with the tilted gravity), 'ft-calib' (force_torque_tools "
        "ft_calib YAML: "
        "bias, gripper_mass, gripper_com_pose). What a format cannot hold is printed and written "
        "as comments. "
        "Robot payloads, centre of mass in the flange frame through the mount and the URDF: "
        "'franka-load' "
        "(franka_msgs/srv/SetLoad request: mass, center_of_mass, load_inertia), 'ur-payload' "
        "(ur_msgs/srv/SetPayload "
        "request for the ROS 2 UR driver, URScript set_payload as a comment; OUT.script: the "
        "URScript line only).",
    )
    parser.add_argument("calibration", metavar="CALIB.json")
    parser.add_argument(
        "--format",
        required=True,
        choices=EXPORT_FORMATS + PAYLOAD_FORMATS,
        dest="fmt",
        help="target format",
    )
    parser.add_argument("-o", "--output", required=True, metavar="OUT.yaml")
    parser.add_argument(
        "--frame-id",
        metavar="NAME",
        help="sensor frame name in ROS (default: the calibration's sensor frame)",
    )
    parser.add_argument(
        "--world-frame",
        metavar="NAME",
        help="gravity-compensation: fixed frame (default: the URDF root link)",
    )
    parser.add_argument(
        "--node-name",
        metavar="NAME",
        help="ROS 2 node the parameters belong to (admittance, gravity-compensation)",
    )
    payload = parser.add_argument_group("robot payloads (franka-load, ur-payload)")
    payload.add_argument(
        "--flange-frame",
        metavar="NAME",
        help="flange frame of the URDF (default: tool0, flange, panda_link8 "
        "or fr3_link8 when present, else the sensor frame's parent)",
    )
    payload.add_argument(
        "--inertia",
        type=float,
        nargs=6,
        metavar=("IXX", "IYY", "IZZ", "IXY", "IXZ", "IYZ"),
        help="tool inertia about its centre of mass in flange axes [kg·m²] (default: unknown, "
        "written as zero)",
    )
    payload.add_argument(
        "--end-effector",
        type=float,
        nargs=4,
        metavar=("MASS", "CX", "CY", "CZ"),
        help="franka-load: subtract the end effector the controller already models (libfranka "
        "m_ee, F_x_Cee) [kg, m, flange frame]",
    )
    payload.add_argument(
        "--sensor-body",
        type=float,
        nargs=4,
        metavar=("MASS", "CX", "CY", "CZ"),
        help="franka-load: add the sensor's own body above its measuring plane (datasheet) "
        "[kg, m, flange frame]",
    )
    add_arm_arguments(parser)
    parser.set_defaults(func=run)


def run(args) -> int:
    calibration = load_calibration(args.calibration)
    if args.fmt in PAYLOAD_FORMATS:
        arm = arm_for_calibration(args, calibration) or Arm.default()
        bodies = [
            None if values is None else RigidBody.point(values[0], values[1:])
            for values in (getattr(args, "end_effector", None), getattr(args, "sensor_body", None))
        ]
        export_payload(
            calibration,
            arm,
            args.output,
            args.fmt,
            args.flange_frame,
            args.inertia,
            end_effector=bodies[0],
            sensor_body=bodies[1],
        )
        payload = controller_payload(
            calibration, arm, args.fmt, args.flange_frame, args.inertia, *bodies
        )
        com = ", ".join(f"{value:.6g}" for value in payload.center_of_mass)
        print(
            f"wrote {args.fmt} to {args.output}: mass {payload.mass:.6g} kg, centre of mass "
            f"[{com}] m "
            f"in the flange frame {payload.flange_frame!r}"
        )
        return 0
    export_calibration(
        calibration,
        args.output,
        args.fmt,
        frame_id=args.frame_id,
        world_frame=args.world_frame,
        node_name=args.node_name,
    )
    print(f"wrote {args.fmt} parameters to {args.output}")
    for note in export_notes(calibration, args.fmt):
        print(f"  note: {note}")
    return 0
