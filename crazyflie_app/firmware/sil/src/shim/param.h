/* The firmware's own param.h with its real PARAM_GROUP_START / PARAM_ADD macros in this host build (see
 * log.h beside it): every PARAM_GROUP of a compiled firmware file lands in a `.param.<group>` section, which
 * sil_tables.ld gathers between __param_start and __param_stop. */
#pragma once
#ifdef UNIT_TEST_MODE
#undef UNIT_TEST_MODE
#include_next "param.h"
#define UNIT_TEST_MODE
#else
#include_next "param.h"
#endif
