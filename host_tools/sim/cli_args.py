"""Argument helpers shared by the simulator's commands."""
from host_tools import argtypes
from host_tools.errors import ForaNavError
from host_tools.sim.camera import CameraModel, SENSOR_MODES
from host_tools.sim.world import NO_EFFECTS, SENSOR_EFFECTS

EFFECT_PRESETS = {"none": NO_EFFECTS, "sensor": SENSOR_EFFECTS}
MOUNT_OFFSET_M = argtypes.float_range(-1.0, 1.0)  # a camera on a MAV sits within a metre of its centre
ALTITUDE_M = argtypes.float_range(0.05, 100.0)  # above the ground, below where a tree is a pixel


def add_camera_arguments(parser):
    parser.add_argument("--width", type=int, default=352, help="sensor mode width (default 352)")
    parser.add_argument("--height", type=int, default=288, help="sensor mode height (default 288)")
    parser.add_argument("--mount-offset", type=MOUNT_OFFSET_M, nargs=2, default=(0.0, 0.0), metavar=("FWD", "LEFT"),
                        action=argtypes.Once,
                        help="camera position relative to the MAV, body frame metres (default 0 0)")
    parser.add_argument("--effects", choices=sorted(EFFECT_PRESETS), default="none",
                        help="per-frame camera effects: none (default) or sensor (blur, noise, JPEG)")


def camera_from_args(args):
    if (args.width, args.height) not in SENSOR_MODES:
        raise ForaNavError("--width/--height: unknown sensor mode %dx%d (expected one of %s)"
                           % (args.width, args.height, ", ".join("%dx%d" % m for m in SENSOR_MODES)))
    return CameraModel(args.width, args.height, tuple(args.mount_offset))
