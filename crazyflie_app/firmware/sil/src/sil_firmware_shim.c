/* The thin shim between the firmware's own C files (commander.c, supervisor.c, the controller, the Kalman
 * core, power distribution) and the host: the FreeRTOS calls they make (the tick count and the 1-deep
 * queues of commander.c), the motor driver (the plant's motors), the console (DEBUG_PRINT lines are kept
 * for the host to read), what the high-level commander needs of FreeRTOS, CRTP and the memory subsystem, and
 * the services that are not flown here (the CRTP emergency stop, deck faults), each answering as a firmware
 * without them would. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "FreeRTOS.h"
#include "queue.h"
#include "task.h"

#include "crtp.h"
#include "crtp_commander.h"
#include "crtp_commander_high_level.h"
#include "mem.h"
#include "crtp_supervisor.h"
#include "deck_supervisor.h"
#include "motors.h"
#include "planner.h"

#include "sil_shim.h"

#define CONSOLE_CAPACITY 8192

static uint32_t tickCount;
static uint16_t motorRatios[NBR_OF_MOTORS];
static char console[CONSOLE_CAPACITY];
static int consoleLength;
static int assertFailures;

/* -- FreeRTOS ------------------------------------------------------------------------------------------ */

TickType_t xTaskGetTickCount(void) { return tickCount; }

void silShimSetTick(uint32_t tick) { tickCount = tick; }

/* commander.c's queues hold one item and are only overwritten and peeked: the item lives in the storage
 * the caller allocated (STATIC_MEM_QUEUE_ALLOC), its size in the StaticQueue_t the caller also gave. */
typedef struct {
  uint8_t *storage;
  UBaseType_t itemSize;
} HostQueue;

_Static_assert(sizeof(HostQueue) <= sizeof(StaticQueue_t), "a host queue fits in the static queue buffer");

QueueHandle_t xQueueGenericCreateStatic(const UBaseType_t uxQueueLength, const UBaseType_t uxItemSize,
                                        uint8_t *pucQueueStorage, StaticQueue_t *pxStaticQueue,
                                        const uint8_t ucQueueType) {
  (void)uxQueueLength;
  (void)ucQueueType;
  HostQueue *queue = (HostQueue *)pxStaticQueue;
  queue->storage = pucQueueStorage;
  queue->itemSize = uxItemSize;
  memset(queue->storage, 0, uxItemSize);
  return (QueueHandle_t)queue;
}

BaseType_t xQueueGenericSend(QueueHandle_t xQueue, const void *const pvItemToQueue, TickType_t xTicksToWait,
                             const BaseType_t xCopyPosition) {
  (void)xTicksToWait;
  (void)xCopyPosition;
  HostQueue *queue = (HostQueue *)xQueue;
  if (queue->itemSize > 0) {  /* a mutex (the high-level commander's lock) has no item */
    memcpy(queue->storage, pvItemToQueue, queue->itemSize);
  }
  return pdTRUE;
}

BaseType_t xQueuePeek(QueueHandle_t xQueue, void *const pvBuffer, TickType_t xTicksToWait) {
  (void)xTicksToWait;
  HostQueue *queue = (HostQueue *)xQueue;
  memcpy(pvBuffer, queue->storage, queue->itemSize);
  return pdTRUE;
}

/* -- the motor driver: the plant reads what the stabilizer set --------------------------------------- */

void motorsSetRatio(uint32_t id, uint16_t ratio) { motorRatios[id] = ratio; }

uint16_t motorsGetRatio(uint32_t id) { return motorRatios[id]; }

void motorsStop(void) { memset(motorRatios, 0, sizeof(motorRatios)); }

uint16_t motorsGetRPM(uint32_t motorId) {
  (void)motorId;
  return MOTORS_RPM_INVALID;
}

/* The Bolt build has no CONFIG_ENABLE_THRUST_BAT_COMPENSATED: motors.c passes the thrust through. */
float motorsCompensateBatteryVoltage(uint32_t id, float iThrust, float supplyVoltage) {
  (void)id;
  (void)supplyVoltage;
  return iThrust;
}

/* -- console: DEBUG_PRINT is printf in UNIT_TEST_MODE; the link redirects printf/puts here ------------ */

static void consoleAppend(const char *text, int length) {
  if (length > CONSOLE_CAPACITY - consoleLength) {
    length = CONSOLE_CAPACITY - consoleLength;  /* the host reads often; a flood loses its tail */
  }
  memcpy(console + consoleLength, text, (size_t)length);
  consoleLength += length;
}

int __wrap_printf(const char *format, ...) {
  char line[256];
  va_list args;
  va_start(args, format);
  int length = vsnprintf(line, sizeof(line), format, args);
  va_end(args);
  if (length < 0) {
    return length;
  }
  length = length < (int)sizeof(line) ? length : (int)sizeof(line) - 1;
  consoleAppend(line, length);
  return length;
}

int __wrap_puts(const char *text) {
  consoleAppend(text, (int)strlen(text));
  consoleAppend("\n", 1);
  return 1;
}

int __wrap_putchar(int c) {
  const char ch = (char)c;
  consoleAppend(&ch, 1);
  return c;
}

int silShimConsoleRead(char *buffer, int size) {
  int length = consoleLength < size ? consoleLength : size;
  memcpy(buffer, console, (size_t)length);
  memmove(console, console + length, (size_t)(consoleLength - length));
  consoleLength -= length;
  return length;
}

void assertFail(char *exp, char *file, int line) {
  assertFailures++;
  __wrap_printf("ASSERT: %s (%s:%d)\n", exp, file, line);
}

int silShimAssertFailures(void) { return assertFailures; }

int silShimConsolePending(void) { return consoleLength; }

/* -- what the high-level commander (sil_high_level.c) asks of FreeRTOS, CRTP, the memory subsystem ------ */

/* Its CRTP task is never created: the host hands it packets (sil_high_level_command). */
TaskHandle_t xTaskCreateStatic(TaskFunction_t pxTaskCode, const char *const pcName, const uint32_t ulStackDepth,
                               void *const pvParameters, UBaseType_t uxPriority, StackType_t *const puxStackBuffer,
                               StaticTask_t *const pxTaskBuffer) {
  (void)pxTaskCode;
  (void)pcName;
  (void)ulStackDepth;
  (void)pvParameters;
  (void)uxPriority;
  (void)puxStackBuffer;
  return (TaskHandle_t)pxTaskBuffer;
}

void crtpInitTaskQueue(CRTPPort taskPort) { (void)taskPort; }
int crtpReceivePacketBlock(CRTPPort taskPort, CRTPPacket *p) {
  (void)taskPort;
  (void)p;
  return -1;
}
int crtpSendPacketBlock(CRTPPacket *p) {
  (void)p;
  return 0;
}

/* One loop, no preemption: its trajectory lock is never contended. */
QueueHandle_t xQueueCreateMutexStatic(const uint8_t ucQueueType, StaticQueue_t *pxStaticQueue) {
  (void)ucQueueType;
  HostQueue *queue = (HostQueue *)pxStaticQueue;
  queue->storage = NULL;
  queue->itemSize = 0;
  return (QueueHandle_t)queue;
}

BaseType_t xQueueSemaphoreTake(QueueHandle_t xQueue, TickType_t xTicksToWait) {
  (void)xQueue;
  (void)xTicksToWait;
  return pdTRUE;
}

/* The planner's clock: the tick in microseconds (usec_time.h). */
uint64_t usecTimestamp(void) { return (uint64_t)tickCount * 1000u; }

/* mem.c's registry: the trajectory memory's handler is the one sil_high_level.c reaches directly. */
void memoryRegisterHandler(const MemoryHandlerDef_t *handlerDef) { (void)handlerDef; }

/* -- services not flown here --------------------------------------------------------------------------- */

void crtpCommanderInit(void) {}
bool crtpSupervisorIsEmergencyStopRequested(void) { return false; }
uint32_t crtpSupervisorGetEmergencyStopWatchdogNotificationTick(void) { return 0; }
bool deckSupervisorHasFault(void) { return false; }
