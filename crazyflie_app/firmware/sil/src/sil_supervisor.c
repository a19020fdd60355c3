/* supervisor.c built as it is, in this translation unit so the host can read the state it keeps in a
 * static (the firmware exposes only yes/no questions about it: supervisorIsFlying(), ...). */
#include "supervisor.c"

#include "sil_shim.h"

int silSupervisorState(void) { return (int)supervisorMem.state; }
