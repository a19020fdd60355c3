/* The firmware's own log.h with its real LOG_GROUP_START / LOG_ADD macros, also in this host build (which
 * defines UNIT_TEST_MODE for DEBUG_PRINT and the firmware's other host paths, and there log.h would empty
 * the macros). Every LOG_GROUP of a compiled firmware file then lands in a `.log.<group>` section, which
 * sil_tables.ld gathers between __log_start and __log_stop for the host to enumerate (sil/tables.py). */
#pragma once
#ifdef UNIT_TEST_MODE
#undef UNIT_TEST_MODE
#include_next "log.h"
#define UNIT_TEST_MODE
#else
#include_next "log.h"
#endif
