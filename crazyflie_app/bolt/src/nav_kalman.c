/*
 * A constant-velocity Kalman filter on the target's image position (the port of pixel_kalman.py).
 *
 * State x = [u, v, du, dv] (px, px/s), time in real seconds: navKalmanPredict(dt) every control tick with
 * the tick's true duration, navKalmanUpdate(u, v) on each detection of the tracked tree. P is the full 4x4
 * covariance with a Joseph-form update (Navigation.c kept P in a 2x2 array and wrote P[2][2], P[3][3]).
 *
 *   predict:  x = F x               P = F P F' + Q
 *   update:   y = z - H x           S = H P H' + R          K = P H' S^-1
 *             x = x + K y           P = (I - K H) P (I - K H)' + K R K'
 */
#include <math.h>
#include <string.h>

#include "nav_core.h"

/* 4x4 products on row-major arrays (flat pointers: gcc's -fsanitize builds misjudge 2-D array parameters).
 * b[k][j] is b[row * k + column * j]: (4, 1) is b itself, (1, 4) its transpose. */
static void matMul4Strided(const double* a, const double* b, int row, int column, double* out) {
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < 4; j++) {
      double sum = 0.0;
      for (int k = 0; k < 4; k++) {
        sum += a[4 * i + k] * b[row * k + column * j];
      }
      out[4 * i + j] = sum;
    }
  }
}

static void matMul4(const double* a, const double* b, double* out) { matMul4Strided(a, b, 4, 1, out); }

static void matMul4T(const double* a, const double* b, double* out) { matMul4Strided(a, b, 1, 4, out); } /* a b' */

void navKalmanInit(NavKalman* kf, double u, double v, double measurement_std_px, double accel_psd,
                   double initial_velocity_std) {
  memset(kf, 0, sizeof(*kf));
  kf->R = measurement_std_px * measurement_std_px;
  kf->accel_psd = accel_psd;
  kf->x[0] = u;
  kf->x[1] = v;
  kf->P[0][0] = kf->R;
  kf->P[1][1] = kf->R;
  kf->P[2][2] = initial_velocity_std * initial_velocity_std;
  kf->P[3][3] = initial_velocity_std * initial_velocity_std;
}

void navKalmanPredict(NavKalman* kf, double dt) {
  if (!(dt > 0.0)) {
    return; /* dt == 0: nothing to do; the core never passes a negative dt */
  }
  const double F[4][4] = {{1.0, 0.0, dt, 0.0}, {0.0, 1.0, 0.0, dt}, {0.0, 0.0, 1.0, 0.0}, {0.0, 0.0, 0.0, 1.0}};
  const double q = kf->accel_psd;
  const double q11 = q * pow(dt, 3.0) / 3.0, q12 = q * pow(dt, 2.0) / 2.0, q22 = q * dt;
  const double Q[4][4] = {{q11, 0.0, q12, 0.0}, {0.0, q11, 0.0, q12}, {q12, 0.0, q22, 0.0}, {0.0, q12, 0.0, q22}};
  double x[4];
  for (int i = 0; i < 4; i++) {
    double sum = 0.0;
    for (int k = 0; k < 4; k++) {
      sum += F[i][k] * kf->x[k];
    }
    x[i] = sum;
  }
  memcpy(kf->x, x, sizeof(x));
  double FP[4][4], FPFt[4][4];
  matMul4(&F[0][0], &kf->P[0][0], &FP[0][0]);
  matMul4T(&FP[0][0], &F[0][0], &FPFt[0][0]);
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < 4; j++) {
      kf->P[i][j] = FPFt[i][j] + Q[i][j];
    }
  }
  kf->predictions++;
}

void navKalmanUpdate(NavKalman* kf, double u, double v) {
  /* H = [I2 0]: H x = x[0:2], P H' = P[:, 0:2], H P H' = P[0:2, 0:2] */
  const double y0 = u - kf->x[0], y1 = v - kf->x[1];
  const double s00 = kf->P[0][0] + kf->R, s01 = kf->P[0][1], s10 = kf->P[1][0], s11 = kf->P[1][1] + kf->R;
  const double det = s00 * s11 - s01 * s10;
  const double i00 = s11 / det, i01 = -s01 / det, i10 = -s10 / det, i11 = s00 / det;
  double K[4][2];
  for (int i = 0; i < 4; i++) {
    K[i][0] = kf->P[i][0] * i00 + kf->P[i][1] * i10;
    K[i][1] = kf->P[i][0] * i01 + kf->P[i][1] * i11;
  }
  for (int i = 0; i < 4; i++) {
    kf->x[i] = kf->x[i] + (K[i][0] * y0 + K[i][1] * y1);
  }
  double IKH[4][4];
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < 4; j++) {
      const double kh = j < 2 ? K[i][j] : 0.0;
      IKH[i][j] = (i == j ? 1.0 : 0.0) - kh;
    }
  }
  double A[4][4], AP[4][4];
  matMul4(&IKH[0][0], &kf->P[0][0], &A[0][0]);
  matMul4T(&A[0][0], &IKH[0][0], &AP[0][0]);
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < 4; j++) {
      /* K R K' with R = r I */
      kf->P[i][j] = AP[i][j] + (K[i][0] * kf->R * K[j][0] + K[i][1] * kf->R * K[j][1]);
    }
  }
  kf->updates++;
}
