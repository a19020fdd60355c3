/*
 * ForaNav flight app for the Crazyflie Bolt: the thin firmware adapter around the pure navigation core
 * (nav_core.h, nav_*.c), the C twin of crazyflie_app/app/navigation.py.
 *
 * appMain waits for the system, checks the decks (deck.bcFlow2 required, deck.bcLoco advised), resolves the
 * stateEstimate log ids once, waits 3 s, waits for the camera (app.camWaitMs, else NO_CAMERA: never armed),
 * requests arming (the Bolt requires it: CONFIG_MOTORS_REQUIRE_ARMING), then every 10 ms reads the estimate,
 * steps the core and sends its setpoint with commanderSetSetpoint(..., COMMANDER_PRIORITY_EXTRX). The camera
 * task reads the JeVois' text lines from UART2 (115200 baud; the driver's receive buffer holds 200 bytes, so it
 * is drained every 10 ms) and feeds them to the core's line assembler and parser. The two tasks share the core
 * under a mutex.
 *
 * PARAM_GROUP(app) and LOG_GROUP(app) are in foranav_params.c and foranav_log.c; the console lines are the
 * Python app's (navFormatEvent).
 */
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "FreeRTOS.h"
#include "semphr.h"
#include "task.h"

#include "app.h"
#include "commander.h"
#include "log.h"
#include "param.h"
#include "static_mem.h"
#include "supervisor.h"
#include "uart2.h"

#define DEBUG_MODULE "FORANAV"
#include "debug.h"

#include "foranav_app.h"
#include "foranav_path.h"

#define BOOT_DELAY_MS 2000         /* Navigation.c: wait 2 s, then check the decks */
#define PRE_TAKEOFF_DELAY_MS 3000  /* ... and 3 s more before take-off */
#define APP_PERIOD_MS 10           /* the main loop */
#define CAMERA_PERIOD_MS 10        /* UART2 polling: 200 bytes hold 17 ms of 115200 baud */
#define CAMERA_WAIT_POLL_MS 10     /* pre-flight camera check */
#define START_POLL_MS 10           /* app.start 0: how often the app looks whether a client started it */
#define CAMERA_TASK_PRI 1
#define CAMERA_TASK_STACKSIZE 800 /* words: the frame path (association, events) needs ~2 kB */
#define UART2_BAUDRATE 115200
#define UART_CHUNK 64
#define LOG_VARID_INVALID 0xffffu
#define EVENT_LINE_LENGTH 160

static NavCore core;
static NavCameraInput camera;
static SemaphoreHandle_t coreMutex;
static StaticSemaphore_t coreMutexBuffer;
static logVarId_t estimateIds[6];
static bool estimateReady;
static setpoint_t setpoint;
STATIC_MEM_TASK_ALLOC(foranavCameraTask, CAMERA_TASK_STACKSIZE);

static void setHoverSetpoint(setpoint_t* sp, float vx, float vy, float z, float yaw) {
  sp->mode.x = modeVelocity;
  sp->mode.y = modeVelocity;
  sp->mode.z = modeAbs;
  sp->mode.yaw = modeAbs;
  sp->velocity.x = vx;
  sp->velocity.y = vy;
  sp->position.z = z;
  sp->attitude.yaw = yaw;
  sp->velocity_body = true;
}

static NavPose readPose(void) {
  NavPose p;
  p.x = logGetFloat(estimateIds[0]);
  p.y = logGetFloat(estimateIds[1]);
  p.z = logGetFloat(estimateIds[2]);
  p.yaw_deg = logGetFloat(estimateIds[3]);
  p.vx = logGetFloat(estimateIds[4]);
  p.vy = logGetFloat(estimateIds[5]);
  return p;
}

static void printEvents(void) {
  NavEvent event;
  char line[EVENT_LINE_LENGTH];
  while (navCoreDrainEvents(&core, &event, 1) == 1) {
    navFormatEvent(&event, line, sizeof(line));
    DEBUG_PRINT("%s\n", line);
  }
}

/* The camera task: drain UART2 every 10 ms into the core's camera input. */
static void cameraTask(void* arg) {
  (void)arg;
  uint8_t buffer[UART_CHUNK];
  for (;;) {
    xSemaphoreTake(coreMutex, portMAX_DELAY);
    const int32_t now = (int32_t)xTaskGetTickCount();
    const NavPose pose = estimateReady ? readPose() : (NavPose){0};
    int received;
    /* timeout 1 tick: with 0 the driver returns nothing at all */
    while ((received = uart2GetDataWithTimeout(sizeof(buffer), buffer, M2T(1))) > 0) {
      size_t used = 0;
      while (used < (size_t)received) {
        bool frameDone = false;
        used += navCameraInputFeed(&camera, &core, buffer + used, (size_t)received - used, now, &pose,
                                   estimateReady, &frameDone);
      }
    }
    navCameraInputEndBatch(&camera, &core, now, &pose, estimateReady);
    printEvents();
    xSemaphoreGive(coreMutex);
    vTaskDelay(M2T(CAMERA_PERIOD_MS));
  }
}

void appMain(void) {
  static const double pathXy[] = FORANAV_PATH_XY;
  NavParams params;
  navParamsDefaults(&params);
  params.altitude_m = FORANAV_ALTITUDE_M;
  foranavParamsFromCore(&params);
  if (!navCoreInit(&core, &params, pathXy, FORANAV_PATH_WAYPOINTS)) {
    DEBUG_PRINT("foranav_path.h: 2 to %d waypoints needed, aborting\n", NAV_MAX_WAYPOINTS);
    return;
  }
  navCameraInputInit(&camera, FORANAV_TARGET_LABEL);
  coreMutex = xSemaphoreCreateMutexStatic(&coreMutexBuffer);
  uart2Init(UART2_BAUDRATE);
  STATIC_MEM_TASK_CREATE(foranavCameraTask, cameraTask, "FORANAV_CAM", NULL, CAMERA_TASK_PRI);

  DEBUG_PRINT("ForaNav app started, waiting for the system\n");
  vTaskDelay(M2T(BOOT_DELAY_MS));
  const paramVarId_t flowId = paramGetVarId("deck", "bcFlow2");
  const paramVarId_t locoId = paramGetVarId("deck", "bcLoco");
  if (!PARAM_VARID_IS_VALID(flowId) || !paramGetUint(flowId)) {
    DEBUG_PRINT("No flow deck installed, aborting\n");
    xSemaphoreTake(coreMutex, portMAX_DELAY);
    navCoreAbortNoDeck(&core, (int32_t)xTaskGetTickCount());
    printEvents();
    xSemaphoreGive(coreMutex);
    return; /* the app task parks */
  }
  if (!PARAM_VARID_IS_VALID(locoId) || !paramGetUint(locoId)) {
    DEBUG_PRINT("No Loco deck: flying on Flow dead reckoning, expect drift\n");
  }
  static const char* const names[6] = {"x", "y", "z", "yaw", "vx", "vy"};
  for (int i = 0; i < 6; i++) {
    estimateIds[i] = logGetVarId("stateEstimate", names[i]);
    if (estimateIds[i] == LOG_VARID_INVALID) {
      DEBUG_PRINT("stateEstimate not available, aborting\n");
      return;
    }
  }
  xSemaphoreTake(coreMutex, portMAX_DELAY);
  estimateReady = true;
  xSemaphoreGive(coreMutex);
  /* app.start 0: on the ground, motors off, until a client (cflib, cfclient) writes app.start = 1 */
  for (bool waiting = false;; waiting = true) {
    xSemaphoreTake(coreMutex, portMAX_DELAY);
    foranavParamsToCore(&core.params);
    const bool start = core.params.start != 0;
    xSemaphoreGive(coreMutex);
    if (start) {
      if (waiting) {
        DEBUG_PRINT("Started by app.start\n");
      }
      break;
    }
    if (!waiting) {
      DEBUG_PRINT("Waiting for app.start = 1\n");
    }
    vTaskDelay(M2T(START_POLL_MS));
  }
  vTaskDelay(M2T(PRE_TAKEOFF_DELAY_MS));
  /* a camera never heard is a camera lost: flying the path blind would "complete" nothing */
  for (int32_t waited = 0;; waited += CAMERA_WAIT_POLL_MS) {
    xSemaphoreTake(coreMutex, portMAX_DELAY);
    foranavParamsToCore(&core.params);
    const bool alive = navCameraInputAlive(&camera, &core.params, (int32_t)xTaskGetTickCount());
    const bool give_up = !alive && waited >= core.params.camera_wait_ms;
    if (give_up) {
      char seconds[16];
      navFormatFixed(seconds, sizeof(seconds), (double)core.params.camera_wait_ms / 1000.0, 1);
      DEBUG_PRINT("No camera heard for %s s, not taking off\n", seconds);
      navCoreAbortNoCamera(&core, (int32_t)xTaskGetTickCount());
      printEvents();
    }
    xSemaphoreGive(coreMutex);
    if (alive) {
      break;
    }
    if (give_up) {
      return; /* never armed: the Bolt stays on the ground */
    }
    if (waited == 0) {
      DEBUG_PRINT("Waiting for the camera\n");
    }
    vTaskDelay(M2T(CAMERA_WAIT_POLL_MS));
  }
  /* the last check passed. The Bolt requires arming: until armed, the supervisor replaces every setpoint by
   * the null one */
  if (!supervisorRequestArming(true)) {
    DEBUG_PRINT("Arming refused by the supervisor, aborting\n");
    return;
  }
  DEBUG_PRINT("Armed\n");
  xSemaphoreTake(coreMutex, portMAX_DELAY);
  navCoreStart(&core, (int32_t)xTaskGetTickCount());
  printEvents();
  xSemaphoreGive(coreMutex);
  for (;;) {
    xSemaphoreTake(coreMutex, portMAX_DELAY);
    foranavParamsToCore(&core.params); /* PARAM writes from the client take effect on the next tick */
    const NavPose pose = readPose();
    const NavCommand command = navCoreStep(&core, (int32_t)xTaskGetTickCount(), &pose);
    if (command.kind == NAV_CMD_HOVER) {
      setHoverSetpoint(&setpoint, (float)command.vx, (float)command.vy, (float)command.z, 0.0f);
    } else {
      memset(&setpoint, 0, sizeof(setpoint)); /* null setpoint: motors off */
    }
    commanderSetSetpoint(&setpoint, COMMANDER_PRIORITY_EXTRX);
    foranavLogRefresh(&core, &camera);
    printEvents();
    xSemaphoreGive(coreMutex);
    vTaskDelay(M2T(APP_PERIOD_MS));
  }
}
