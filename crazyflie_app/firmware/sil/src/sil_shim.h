/* What the loop (sil_stabilizer.c) asks of the firmware shim (sil_firmware_shim.c). */
#pragma once
#include <stdint.h>

void silShimSetTick(uint32_t tick);
int silShimConsoleRead(char *buffer, int size);
int silShimAssertFailures(void);
int silSupervisorState(void);
int silShimConsolePending(void);
