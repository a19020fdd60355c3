"""The navigation core's records: the phases, the pose / command / detection tuples, every parameter
(``NavigationParams``, exported by the app as PARAMs), the decisions (``Event``) and the counters. Imported
through ``crazyflie_app.app.navigation_core`` by everything outside the core."""
from dataclasses import dataclass
from typing import NamedTuple

PHASE_BOOT, PHASE_TAKEOFF, PHASE_FOLLOW_PATH, PHASE_APPROACH, PHASE_RECOVERY, PHASE_RETURN_TO_PATH, \
    PHASE_LAND, PHASE_DONE, PHASE_NO_DECK, PHASE_NO_CAMERA = range(10)
PHASE_NAMES = ("BOOT", "TAKEOFF", "FOLLOW_PATH", "APPROACH", "RECOVERY", "RETURN_TO_PATH", "LAND", "DONE",
               "NO_DECK", "NO_CAMERA")

COLUMN_FACTOR = 1.5  # paper: planting column half-width, in crown sizes (path_following.within_column)
POSE_HISTORY_LENGTH = 128  # ticks of pose history kept for latency compensation (~1.3 s at 100 Hz)


class Pose(NamedTuple):
    """The state estimate (a tuple, as the C core takes it)."""
    x: float  # m
    y: float  # m
    z: float  # m
    yaw_deg: float
    vx: float  # m/s
    vy: float  # m/s


class Command(NamedTuple):
    """What the core asks for: kind "hover" (body vx, vy in m/s; z absolute in m) or "null" (motors off)."""
    kind: str
    vx: float
    vy: float
    z: float


class Detection(NamedTuple):
    """A detection's image position, px."""
    u: float
    v: float


@dataclass
class NavigationParams:
    """Every threshold and speed law; the app exports each as a PARAM (``app.<name>``, units in the table)."""
    altitude_m: float = 1.25  # paper flight tests
    takeoff_tolerance_m: float = 0.05  # height error that counts as "at altitude"
    takeoff_settle_ms: int = 1000  # held that long before the path starts
    land_height_m: float = 0.5  # Navigation.c lands in two 3 s steps: 0.5 m ...
    land_final_m: float = 0.15  # ... then 0.15 m (here: from 0.15 m down to the ground), then motors off
    land_step_ms: int = 3000
    arrival_min_speed: float = 0.02  # the follow law never crawls slower than this towards a waypoint
    cruise_speed: float = 0.10  # paper: <= 0.1 m/s
    waypoint_tolerance_m: float = 0.03  # Navigation.c is_at_target_mainroad
    lookahead_m: float = 0.15
    approach_speed: float = 0.10
    servo_gain: float = 0.8  # 1/s: body velocity per metre of image offset
    capture_radius_px: float = 40.0  # tau (paper / Navigation.c)
    settle_radius_px: float = 6.0
    settle_dwell_ms: int = 600
    settle_speed: float = 0.02
    settle_relax: float = 1.0  # px/s: after settle_grace_ms captured, the settle radius (and speed) grow,
    settle_grace_ms: int = 8000  # so gusts cannot keep the MAV from ever finishing a tree (cap: tau)
    servo_integral: float = 0.3  # 1/s^2: integral action of the servo law (rejects steady drift and wind)
    servo_integral_band: float = 3.0  # settle radii: the servo integrates the offset only inside this band
    recovery_distance_m: float = 0.7  # delta (Navigation.c 0.7 m switch)
    # 1.5 s = 13 frames at the paper's 9 fps. With the module in the loop, a tree right under the camera is
    # found in only ~60 % of frames for some trees (Map 3 Tree 5), in runs of misses; at 600 ms the app fell
    # into recovery again and again and never settled. The filter rides through the gaps meanwhile.
    lost_timeout_ms: int = 1500
    recovery_timeout_ms: int = 15000
    target_timeout_ms: int = 60000  # a target not reached this long after selection is abandoned: no endless
    #                                 approach/recovery cycles on a flickering detection, the mission goes on
    recovery_speed: float = 0.10
    return_tolerance_m: float = 0.05
    merge_radius_m: float = 0.45  # Navigation.c same-tree distance
    # two detections of ONE frame this close are one crown seen twice (at 1.0 m a 0.38 m crown spans 120 px
    # and the module reported two windows 0.15 m apart on it: the app stored two trees and reached one twice);
    # distinct trees stand at least a crown (crownSize 0.35 m) apart, clusters 0.35-0.47 m. Duplicates seen
    # 0.05-0.18 m apart; a cluster pair 0.47 m apart with 0.1 m edge errors on each still stays 0.27 m apart
    duplicate_radius_m: float = 0.25
    crown_size_m: float = 0.35
    column_factor: float = COLUMN_FACTOR  # paper: 1.5 x crown size
    # centre-to-centre distance of adjacent rows (a map's row_spacing_m); the column is at most half of it wide
    # (a tree belongs to its nearest row). 0: not given, the paper's 1.5 crowns alone
    row_spacing_m: float = 0.0
    # re-anchoring (path_following): the row line is corrected at each tree reached from at least this many
    # trees seen at that instant (the reached one and the column's trees in view). 1: a row's next tree is
    # often not in view yet when one is reached, and waiting for two let the drift carry the next trees out
    # of the column (tuning sweep). 0: off (the waypoints are flown in the estimate's frame, as before).
    # Off by default for now: on (1, as measured in docs/results.md) the vision flight of Map 1 with garbage
    # lines (test_vision_camera_flights, seed 2) visits the non-target beside Tree 3; set app.anchorMin 1 to fly it
    anchor_min_trees: int = 0
    # ... each correction moving the line this fraction of the way: a tree planted off its row (Map 1's Tree 3,
    # 0.12 m) must not pull the line enough to take in a palm beside the row (Map 1's Tree 7, 0.63 m off);
    # the drift, growing over several trees, is still followed
    anchor_gain: float = 0.5
    min_hits: int = 2
    tree_capacity: int = 32
    visited_capacity: int = 64
    cam_width_px: int = 352
    cam_height_px: int = 288
    cam_scale: float = 0.0031  # m per px per m of height at 352 px width (DESIGN.md)
    cam_offset_x_m: float = 0.0  # camera mount, body forward
    cam_offset_y_m: float = 0.0  # camera mount, body left
    cam_latency_ms: int = 50
    kf_measurement_std_px: float = 3.0
    kf_accel_psd: float = 400.0  # px^2/s^3
    link_hold_ms: int = 1000  # camera silent this long (9 frames at the paper's 9 fps): hold position
    link_land_ms: int = 10000  # ... this long: give up and land
    # used by the firmware layer (navigation.py), kept here with every other PARAM:
    camera_wait_ms: int = 20000  # before take-off: camera unheard this long -> NO_CAMERA, never take off
    #                              (0: take off without waiting, e.g. a replayed clip that starts in flight)
    frame_capacity: int = 64  # detections kept per frame; more before MARK STOP are dropped (counted)
    start: int = 1  # 0: after its deck checks the app waits on the ground, motors off, until a client writes 1

    @property
    def focal_px(self) -> float:
        return focal_px(self.cam_scale, self.cam_width_px)


# A client may write any value into a PARAM (cfclient, cflib: docs/crtp.md); the camera model takes camScale and
# camWidth at the nearest value it can divide by, so a write of 0 gives wrong geometry, never a crash.
CAM_SCALE_MIN = 1e-4  # m per px per m of height: a 10,000 px focal length
CAM_WIDTH_MIN_PX = 1


def focal_px(cam_scale: float, cam_width_px: int) -> float:
    """The focal length in pixels of the camera model (DESIGN.md): 1 / camScale at 352 px, scaled with the width."""
    scale = cam_scale if cam_scale > CAM_SCALE_MIN else CAM_SCALE_MIN  # as nav_params.c: NaN too
    width = cam_width_px if cam_width_px > CAM_WIDTH_MIN_PX else CAM_WIDTH_MIN_PX
    return (1.0 / scale) * width / 352.0


@dataclass
class Event:
    """A decision worth a console line (and a telemetry STATUSTEXT)."""
    kind: str  # tree_added, tree_evicted, target_selected, tree_reached, recovery, reacquired, abandoned, ...
    t_ms: int
    tree_id: int = 0
    x: float = 0.0
    y: float = 0.0
    detail: str = ""


@dataclass
class Counters:
    detections: int = 0
    out_of_column: int = 0
    on_visited: int = 0
    reached: int = 0
    recoveries: int = 0
    abandoned: int = 0
    link_losses: int = 0
    duplicates: int = 0  # detections merged into another one of the same frame (merge_duplicates)

