"""Write the flight path of a map as the Bolt app's compiled-in path (crazyflie_app/bolt/src/foranav_path.h).

    python -m host_tools.bolt_path map1 > crazyflie_app/bolt/src/foranav_path.h

On the Bolt the path F, the flight height and the target species are constants of the build (the Python
app gets them from the map); rebuild (`make bolt`) after changing them.
"""
import sys

from host_tools.errors import ForaNavError
from host_tools.maps import load_map

MAX_WAYPOINTS = 64  # NAV_MAX_WAYPOINTS in nav_core.h
HEADER = """/* The path F of the ForaNav Bolt app, from map %(map)s (python -m host_tools.bolt_path %(map)s). */
#ifndef FORANAV_PATH_H
#define FORANAV_PATH_H

#define FORANAV_PATH_WAYPOINTS %(count)d
/* x0, y0, x1, y1, ... in metres, world frame (take-off at the first waypoint) */
#define FORANAV_PATH_XY {%(xy)s}
#define FORANAV_ALTITUDE_M %(altitude)sf
#define FORANAV_TARGET_LABEL "%(label)s" /* N2 lines with another label are ignored */

#endif /* FORANAV_PATH_H */
"""


def path_header(map_name: str) -> str:
    """foranav_path.h for a built-in map name or a map file (ForaNavError for a bad one)."""
    pmap = load_map(map_name)
    if len(pmap.waypoints) > MAX_WAYPOINTS:
        raise ForaNavError("%s: waypoints: the Bolt app takes at most %d" % (map_name, MAX_WAYPOINTS))
    xy = ", ".join("%.4f, %.4f" % (float(x), float(y)) for x, y in pmap.waypoints)
    return HEADER % {"map": map_name, "count": len(pmap.waypoints), "xy": xy,
                     "altitude": repr(float(pmap.altitude_m)), "label": pmap.target_species or ""}


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m host_tools.bolt_path MAP > crazyflie_app/bolt/src/foranav_path.h", file=sys.stderr)
        return 2
    try:
        text = path_header(args[0])
    except ForaNavError as err:
        print("error: %s" % err, file=sys.stderr)
        return 2
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
