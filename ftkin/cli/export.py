"""``ftkin export CALIB.json --format FORMAT -o OUT.yaml``: parameters for ROS controllers."""

from __future__ import annotations

from ..io.calibration_file import load_calibration
from ..io.export import EXPORT_FORMATS, export_calibration, export_notes


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "export",
        help="write a calibration as ROS controller parameters (admittance, gravity compensation, ft_calib)",
        description="Export a calibration file to: 'admittance' (ros2_controllers admittance_controller "
        "gravity_compensation.*), 'gravity-compensation' (control_toolbox GravityCompensationWrench filter "
        "tool.CoG/mass/gravity_field, with the tilted gravity), 'ft-calib' (force_torque_tools ft_calib YAML: "
        "bias, gripper_mass, gripper_com_pose). What a format cannot hold is printed and written as comments.",
    )
    parser.add_argument("calibration", metavar="CALIB.json")
    parser.add_argument("--format", required=True, choices=EXPORT_FORMATS, dest="fmt", help="target format")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.yaml")
    parser.add_argument("--frame-id", metavar="NAME", help="sensor frame name in ROS (default: the calibration's sensor frame)")
    parser.add_argument("--world-frame", metavar="NAME", help="gravity-compensation: fixed frame (default: the URDF root link)")
    parser.add_argument("--node-name", metavar="NAME", help="ROS 2 node the parameters belong to (admittance, gravity-compensation)")
    parser.set_defaults(func=run)


def run(args) -> int:
    calibration = load_calibration(args.calibration)
    export_calibration(
        calibration, args.output, args.fmt, frame_id=args.frame_id, world_frame=args.world_frame, node_name=args.node_name
    )
    print(f"wrote {args.fmt} parameters to {args.output}")
    for note in export_notes(calibration, args.fmt):
        print(f"  note: {note}")
    return 0
