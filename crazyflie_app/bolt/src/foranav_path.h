/* The path F of the ForaNav Bolt app, from map map1 (python -m host_tools.bolt_path map1). */
#ifndef FORANAV_PATH_H
#define FORANAV_PATH_H

#define FORANAV_PATH_WAYPOINTS 4
/* x0, y0, x1, y1, ... in metres, world frame (take-off at the first waypoint) */
#define FORANAV_PATH_XY {0.3000, 0.4500, 3.9000, 0.4500, 3.9000, -0.4500, 0.3000, -0.4500}
#define FORANAV_ALTITUDE_M 1.25f
#define FORANAV_TARGET_LABEL "oil_palm" /* N2 lines with another label are ignored */

#endif /* FORANAV_PATH_H */
