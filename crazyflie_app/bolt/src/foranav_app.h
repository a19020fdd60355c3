/*
 * The firmware adapter's own header: what foranav_app.c (appMain, the camera task) takes from its PARAM and
 * LOG tables (foranav_params.c, foranav_log.c). Not part of the core.
 */
#ifndef FORANAV_APP_H
#define FORANAV_APP_H

#include "nav_core.h"

void foranavParamsToCore(NavParams* p);         /* PARAM variables -> the core (every tick: client writes) */
void foranavParamsFromCore(const NavParams* p); /* the core's values -> PARAM variables (at start) */
void foranavLogRefresh(const NavCore* core, const NavCameraInput* camera); /* LOG variables, every tick */

#endif
