/* Host stand-in for the firmware's src/drivers/interface/motors.h: the part of the motor driver's interface
 * that supervisor.c and stabilizer-side code use, without the STM32 peripheral types. The plant
 * (sil_plant.c) is the motors; sil_motors.c implements these calls on it. */
#pragma once
#include <stdbool.h>
#include <stdint.h>
#include "config.h"
#include "autoconf.h"

#define NBR_OF_MOTORS 4
#define MOTOR_M1 0
#define MOTOR_M2 1
#define MOTOR_M3 2
#define MOTOR_M4 3
#define MOTORS_RPM_INVALID 0xFFFF

void motorsStop(void);
void motorsSetRatio(uint32_t id, uint16_t ratio);
uint16_t motorsGetRatio(uint32_t id);
uint16_t motorsGetRPM(uint32_t motorId);
float motorsCompensateBatteryVoltage(uint32_t id, float iThrust, float supplyVoltage);
