/* Stand-in for Paparazzi's float algebra: the quaternion the JeVois message carries (ForaNav harness). */
#ifndef HARNESS_ALGEBRA_H
#define HARNESS_ALGEBRA_H
struct FloatQuat { float qi, qx, qy, qz; };
#endif
