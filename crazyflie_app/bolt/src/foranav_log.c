/*
 * The app's LOG group (LOG_GROUP(app)), refreshed from the core every tick (foranavLogRefresh). Names and types
 * are the Python app's LOG table (tests/crazyflie_app/bolt/test_c_app.py checks it).
 */
#include <math.h>
#include <stdint.h>

#include "log.h"

#include "foranav_app.h"

/* LOG variables, refreshed every tick */
static struct {
  uint8_t phase;
  uint16_t targetId;
  float targetX;
  float targetY;
  float errU;
  float errV;
  uint8_t captured;
  uint8_t numTrees;
  uint16_t numVisited;
  uint8_t waypoint;
  uint16_t reached;
  uint16_t recoveries;
  uint16_t abandoned;
  uint32_t detections;
  uint32_t outOfColumn;
  uint16_t evicted;
  uint16_t unstored;
  uint32_t duplicates;
  uint32_t frameOverflow;
  uint16_t forgotten;
  uint32_t linkDropped;
  uint16_t linkOpens;
  uint8_t linkLost;
  uint16_t linkLosses;
} appLog;

void foranavLogRefresh(const NavCore* core, const NavCameraInput* camera) {
  const NavTree* target = navCoreTarget(core);
  appLog.phase = (uint8_t)core->phase;
  appLog.targetId = (uint16_t)core->target_id;
  appLog.targetX = target != NULL ? (float)target->x : NAN; /* as the Python app: no target, no position */
  appLog.targetY = target != NULL ? (float)target->y : NAN;
  appLog.errU = (float)core->pixel_error[0];
  appLog.errV = (float)core->pixel_error[1];
  appLog.captured = core->captured ? 1 : 0;
  appLog.numTrees = (uint8_t)core->memory.num_trees;
  appLog.numVisited = (uint16_t)core->memory.num_visited;
  appLog.waypoint = (uint8_t)core->waypoint_index;
  appLog.reached = (uint16_t)core->counters.reached;
  appLog.recoveries = (uint16_t)core->counters.recoveries;
  appLog.abandoned = (uint16_t)core->counters.abandoned;
  appLog.detections = core->counters.detections;
  appLog.outOfColumn = core->counters.out_of_column;
  appLog.evicted = (uint16_t)core->memory.evicted;
  appLog.unstored = (uint16_t)core->memory.unstored;
  appLog.duplicates = core->counters.duplicates;
  appLog.frameOverflow = camera->frame_overflow;
  appLog.forgotten = (uint16_t)core->memory.visited_forgotten;
  appLog.linkDropped = camera->assembler.dropped;
  appLog.linkOpens = 1;
  appLog.linkLost = core->link_lost ? 1 : 0;
  appLog.linkLosses = (uint16_t)core->counters.link_losses;
}

LOG_GROUP_START(app)
/**
 * @brief app phase (navigation_core.PHASE_NAMES) (-)
 */
LOG_ADD(LOG_UINT8, phase, &appLog.phase)
/**
 * @brief id of the target tree t* (0: none) (-)
 */
LOG_ADD(LOG_UINT16, targetId, &appLog.targetId)
/**
 * @brief stored position s_t of the target (m)
 */
LOG_ADD(LOG_FLOAT, targetX, &appLog.targetX)
/**
 * @brief stored position s_t of the target (m)
 */
LOG_ADD(LOG_FLOAT, targetY, &appLog.targetY)
/**
 * @brief filtered image offset e_p, column (px)
 */
LOG_ADD(LOG_FLOAT, errU, &appLog.errU)
/**
 * @brief filtered image offset e_p, row (px)
 */
LOG_ADD(LOG_FLOAT, errV, &appLog.errV)
/**
 * @brief 1 while e_p < captureRadius (-)
 */
LOG_ADD(LOG_UINT8, captured, &appLog.captured)
/**
 * @brief trees in T_d (-)
 */
LOG_ADD(LOG_UINT8, numTrees, &appLog.numTrees)
/**
 * @brief entries in the visited list (-)
 */
LOG_ADD(LOG_UINT16, numVisited, &appLog.numVisited)
/**
 * @brief index of the waypoint being flown to (-)
 */
LOG_ADD(LOG_UINT8, waypoint, &appLog.waypoint)
/**
 * @brief trees reached (-)
 */
LOG_ADD(LOG_UINT16, reached, &appLog.reached)
/**
 * @brief recoveries started (-)
 */
LOG_ADD(LOG_UINT16, recoveries, &appLog.recoveries)
/**
 * @brief trees given up after a failed recovery (-)
 */
LOG_ADD(LOG_UINT16, abandoned, &appLog.abandoned)
/**
 * @brief detections received (-)
 */
LOG_ADD(LOG_UINT32, detections, &appLog.detections)
/**
 * @brief detections outside the planting column (-)
 */
LOG_ADD(LOG_UINT32, outOfColumn, &appLog.outOfColumn)
/**
 * @brief trees evicted from a full T_d (-)
 */
LOG_ADD(LOG_UINT16, evicted, &appLog.evicted)
/**
 * @brief new trees not stored: T_d full of trees of the same frame (-)
 */
LOG_ADD(LOG_UINT16, unstored, &appLog.unstored)
/**
 * @brief detections merged with another of the same frame (-)
 */
LOG_ADD(LOG_UINT32, duplicates, &appLog.duplicates)
/**
 * @brief detections dropped beyond frameCap in a frame (-)
 */
LOG_ADD(LOG_UINT32, frameOverflow, &appLog.frameOverflow)
/**
 * @brief visited entries forgotten from a full list (-)
 */
LOG_ADD(LOG_UINT16, forgotten, &appLog.forgotten)
/**
 * @brief serial lines dropped for length (-)
 */
LOG_ADD(LOG_UINT32, linkDropped, &appLog.linkDropped)
/**
 * @brief times the serial port was (re)opened (-)
 */
LOG_ADD(LOG_UINT16, linkOpens, &appLog.linkOpens)
/**
 * @brief 1 while holding position for a silent camera link (-)
 */
LOG_ADD(LOG_UINT8, linkLost, &appLog.linkLost)
/**
 * @brief times the camera link went silent in flight (-)
 */
LOG_ADD(LOG_UINT16, linkLosses, &appLog.linkLosses)
LOG_GROUP_STOP(app)
