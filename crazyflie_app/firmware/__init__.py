"""An emulation of the Crazyflie firmware services an app uses, deterministic and seeded.

It stands in for the real firmware (bitcraze/crazyflie-firmware >= 2023.06) so that the navigation app can be
run, tested and flown in simulation on a PC. Names follow the C API in snake_case:

=====================================  ================================================================
C (firmware)                           Python (this package)
=====================================  ================================================================
``configTICK_RATE_HZ`` (1000)          ``freertos.TICK_RATE_HZ``
``M2T(ms)`` / ``T2M`` / ``F2T``        ``freertos.m2t`` / ``t2m`` / ``f2t`` (identity at 1 kHz)
``xTaskGetTickCount()``                ``Crazyflie.x_task_get_tick_count()``
``vTaskDelay(ticks)``                  ``yield freertos.v_task_delay(ticks)`` inside a task generator
``xTaskCreate(fn, name, .., prio)``    ``Crazyflie.x_task_create(generator, name, priority)``
``portMAX_DELAY``                      ``freertos.PORT_MAX_DELAY``
``setpoint_t``, ``stab_mode_t``        ``commander.setpoint_t``, ``modeDisable/modeAbs/modeVelocity``
``COMMANDER_PRIORITY_*``               ``commander.COMMANDER_PRIORITY_DISABLE/LOWEST/HIGHLEVEL/CRTP/EXTRX``
``commanderSetSetpoint(sp, prio)``     ``Crazyflie.commander_set_setpoint(sp, priority)``
``commanderRelaxPriority()``           ``Crazyflie.commander_relax_priority()``
``commanderGetInactivityTime()``       ``Crazyflie.commander_get_inactivity_time()``
``supervisorUpdate`` & state machine   ``supervisor.Supervisor.supervisor_update`` (level-out 500 ms, lock 2 s)
``supervisorOverrideSetpoint``         ``supervisor.Supervisor.supervisor_override_setpoint``
``supervisorRequestArming(doArm)``     ``Crazyflie.supervisor_request_arming(do_arm)`` (Bolt: arming required,
                                       disarm after 30 s armed on the ground or 3 s landed)
``uart2Init``/``uart2GetDataWithTimeout``  ``Crazyflie.uart2_init`` / ``uart2_get_data_with_timeout(size, ticks)``
                                       (``attach_uart2(url)`` plugs the wire in; 200-byte RX buffer, drops)
``logGetVarId(group, name)``           ``Crazyflie.log_get_var_id(group, name)`` (0xFFFF if unknown)
``logGetFloat/logGetUint(id)``         ``Crazyflie.log_get_float/log_get_uint(id)`` (assert on bad id)
``paramGetVarId(group, name)``         ``Crazyflie.param_get_var_id(group, name)`` -> ``ParamVarId``
``paramGetUint/Float``, ``paramSet*``  ``LogParamRegistry.param_get_uint/float``, ``param_set_int/float``
``LOG_GROUP_START``/``LOG_ADD``        ``logparam.log_group(group, [log_add(type, name, attr, unit, doc)])``
``PARAM_GROUP_START``/``PARAM_ADD``    ``logparam.param_group(group, [param_add(...)])``
``DEBUG_PRINT(fmt, ...)``              ``Crazyflie.debug_print(module, text)``
``eventTrigger(&event)``               ``Crazyflie.event_trigger(name, **payload)``
``ASSERT(...)`` failure                ``logparam.FirmwareAssertError``
stabilizer loop + PID position ctrl    ``system.Crazyflie._stabilizer_task`` + ``mav_model.MavModel``
``stateEstimate.*``                    ``mav_model.MavModel.estimate`` (truth + noise + bias)
=====================================  ================================================================

What is not emulated: the attitude/rate loops and motor mixing (replaced by a closed-loop velocity model),
the radio itself (CRTP is served over UDP instead, as cflib's udp:// link: ``crtp``, docs/crtp.md), the
high-level commander, the arming spin-up check, and FreeRTOS time slicing between tasks of equal priority.
"""
from crazyflie_app.firmware.commander import (COMMANDER_PRIORITY_CRTP, COMMANDER_PRIORITY_DISABLE,  # noqa: F401
                                              COMMANDER_PRIORITY_EXTRX, COMMANDER_PRIORITY_HIGHLEVEL,
                                              COMMANDER_PRIORITY_LOWEST, modeAbs, modeDisable, modeVelocity,
                                              setpoint_t)
from crazyflie_app.firmware.freertos import f2t, m2t, t2m, v_task_delay, PORT_MAX_DELAY  # noqa: F401
from crazyflie_app.firmware.logparam import FirmwareAssertError, LOG_VARID_INVALID, PARAM_VARID_INVALID  # noqa
from crazyflie_app.firmware.reduced.mav_model import MavModelConfig  # noqa: F401
from crazyflie_app.firmware.system import Crazyflie  # noqa: F401
