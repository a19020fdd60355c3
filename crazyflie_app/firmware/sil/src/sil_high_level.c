/* The firmware's high-level commander (crtp_commander_high_level.c, with planner.c and pptraj*.c compiled
 * beside it) built as it is, in this translation unit so that the host can hand it a port-8 packet the way its
 * CRTP task does (crtpCommanderHighLevelTask: handleCommand(p.data[0], &p.data[1]), the answer's data[3] the
 * result) without running that FreeRTOS task, and reach the trajectory memory through the handler the
 * firmware registers with the memory subsystem. */
#include "crtp_commander_high_level.c"

#include "sil_api.h"

/* A trajectory defined to lie (partly) past the trajectory memory: the firmware takes the definition and
 * start_trajectory then reads whatever follows the memory; on the host that may be unmapped, so the emulation
 * refuses such a definition with EINVAL instead (docs/crtp.md lists this difference). A compressed
 * trajectory's length is only known by walking it: its start must lie inside the memory. */
static bool definitionOutsideMemory(const uint8_t *command) {
  if (command[0] != COMMAND_DEFINE_TRAJECTORY) {
    return false;
  }
  struct data_define_trajectory definition;
  memcpy(&definition, &command[1], sizeof(definition));
  const struct trajectoryDescription *description = &definition.description;
  if (description->trajectoryLocation != TRAJECTORY_LOCATION_MEM) {
    return false;
  }
  const uint64_t offset = description->trajectoryIdentifier.mem.offset;
  uint64_t end = offset + 1;
  if (description->trajectoryType == CRTP_CHL_TRAJECTORY_TYPE_POLY4D) {
    end = offset + (uint64_t)description->trajectoryIdentifier.mem.n_pieces * sizeof(struct poly4d);
  }
  return end > sizeof(trajectories_memory);
}

/* As the task receives it: a CRTP packet's data buffer of CRTP_MAX_DATA_SIZE bytes, whatever the client sent,
 * the rest of the buffer zero (the firmware reads a command's struct from it whatever the packet's size). */
int sil_high_level_command(const uint8_t *payload, int size) {
  uint8_t data[CRTP_MAX_DATA_SIZE + 1];
  memset(data, 0, sizeof(data));
  if (size < 1) {
    return -1;  /* an empty packet: the task would read data[0] of the previous one; the host drops it */
  }
  memcpy(data, payload, (size_t)(size < CRTP_MAX_DATA_SIZE ? size : CRTP_MAX_DATA_SIZE));
  if (definitionOutsideMemory(data)) {
    return EINVAL;
  }
  return handleCommand((enum TrajectoryCommand_e)data[0], &data[1]);
}

uint32_t sil_trajectory_memory_size(void) { return memDef.getSize(0); }

int sil_trajectory_memory_write(uint32_t address, const uint8_t *data, int length) {
  return memDef.write(0, address, (uint8_t)length, data) ? 1 : 0;
}

int sil_trajectory_memory_read(uint32_t address, uint8_t *data, int length) {
  return memDef.read(0, address, (uint8_t)length, data) ? 1 : 0;
}
