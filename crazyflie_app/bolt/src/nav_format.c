/*
 * The console lines of the core's events (navFormatEvent), formatted like the Python app's. The Bolt build
 * defines NAV_NO_PRINTF_FLOAT: newlib-nano has no printf %f there, so the core formats floats itself.
 */
#include <math.h>
#include <string.h>
#ifndef NAV_NO_PRINTF_FLOAT
#include <stdio.h>
#endif

#include "nav_internal.h"

static const char* const PHASE_NAMES[] = {"BOOT", "TAKEOFF", "FOLLOW_PATH", "APPROACH", "RECOVERY",
                                          "RETURN_TO_PATH", "LAND", "DONE", "NO_DECK", "NO_CAMERA"};
static const char* const EVENT_NAMES[] = {"phase", "tree_added", "tree_evicted", "target_selected",
                                          "tree_reached", "recovery", "approach_by_memory", "reacquired",
                                          "abandoned", "waypoint", "link_lost", "link_restored", "revisit",
                                          "tree_absorbed"};

const char* navPhaseName(int32_t phase) {
  return (phase >= 0 && phase <= NAV_PHASE_NO_CAMERA) ? PHASE_NAMES[phase] : "?";
}

const char* navEventKindName(int32_t kind) {
  return (kind >= 0 && kind < NAV_EVENT_KIND_COUNT) ? EVENT_NAMES[kind] : "?";
}

/* Decimal digits of value >= 0 into out (no libc: the Bolt build links no stdio). Returns the length. */
static size_t formatUnsigned(char* out, size_t size, unsigned long value, int min_digits) {
  char digits[24];
  int n = 0;
  do {
    digits[n++] = (char)('0' + value % 10u);
    value /= 10u;
  } while (value > 0u && n < (int)sizeof(digits));
  while (n < min_digits && n < (int)sizeof(digits)) {
    digits[n++] = '0';
  }
  size_t k = 0;
  while (n > 0 && k + 1 < size) {
    out[k++] = digits[--n];
  }
  if (size > 0) {
    out[k] = '\0';
  }
  return k;
}

int navFormatFixed(char* out, size_t size, double value, int decimals) {
#ifndef NAV_NO_PRINTF_FLOAT
  return snprintf(out, size, "%.*f", decimals, value); /* correctly rounded, as Python's '%.3f' */
#else
  unsigned long scale = 1u;
  for (int i = 0; i < decimals; i++) {
    scale *= 10u;
  }
  const double magnitude = fabs(value) * (double)scale;
  if (!(magnitude < 4.0e9)) {
    return (int)formatUnsigned(out, size, 0u, 1); /* out of range for the console: never a real value */
  }
  /* Correctly rounded like printf: the sign of (exact |value| x scale) - (whole + 1/2) is exact with fma
   * (0.0005 is a little above the half: "0.001"); an exact half goes to even (1.25 -> "1.2"). */
  const double a = fabs(value), sc = (double)scale;
  double whole = floor(magnitude);
  if (fma(a, sc, -whole) < 0.0) {
    whole -= 1.0; /* the rounded product reached an integer the exact one is below */
  }
  const double above_half = fma(a, sc, -(whole + 0.5));
  unsigned long scaled = (unsigned long)whole;
  if (above_half > 0.0 || (above_half == 0.0 && (scaled & 1u))) {
    scaled++;
  }
  size_t n = 0;
  if (value < 0.0 && n + 1 < size) {
    out[n++] = '-';
  }
  n += formatUnsigned(out + n, size - n, scaled / scale, 1);
  if (decimals > 0 && n + 1 < size) {
    out[n++] = '.';
    n += formatUnsigned(out + n, size - n, scaled % scale, decimals);
  }
  out[n < size ? n : size - 1] = '\0';
  return (int)n;
#endif
}

/* Appends with bounds: returns the new length (never past size - 1). */
static size_t append(char* out, size_t size, size_t n, const char* text) {
  while (*text != '\0' && n + 1 < size) {
    out[n++] = *text++;
  }
  out[n < size ? n : size - 1] = '\0';
  return n;
}

static size_t appendFixed(char* out, size_t size, size_t n, double value, int decimals) {
  char number[32];
  navFormatFixed(number, sizeof(number), value, decimals);
  return append(out, size, n, number);
}

/* prefix, the value with decimals, suffix */
static size_t appendQuantity(char* out, size_t size, size_t n, const char* prefix, double value, int decimals,
                             const char* suffix) {
  n = append(out, size, n, prefix);
  n = appendFixed(out, size, n, value, decimals);
  return append(out, size, n, suffix);
}

static size_t appendInt(char* out, size_t size, size_t n, long value) {
  char number[24];
  size_t k = 0;
  if (value < 0) {
    number[k++] = '-';
  }
  formatUnsigned(number + k, sizeof(number) - k, value < 0 ? 0ul - (unsigned long)value : (unsigned long)value, 1);
  return append(out, size, n, number);
}

int navFormatEventDetail(const NavEvent* e, char* out, size_t size) {
  size_t n = 0;
  out[0] = '\0';
  switch (e->kind) {
    case NAV_EVENT_PHASE:
      n = append(out, size, n, navPhaseName(e->n));
      break;
    case NAV_EVENT_TREE_EVICTED:
      n = append(out, size, n, e->variant ? "treeCapacity lowered" : "T_d full");
      break;
    case NAV_EVENT_ABANDONED:
      n = append(out, size, n, e->variant ? "unseen: will go back once" : "");
      break;
    case NAV_EVENT_REVISIT:
      n = append(out, size, n, "abandoned while hidden");
      break;
    case NAV_EVENT_TREE_ABSORBED:
      n = append(out, size, n, "reached tree ");
      n = appendInt(out, size, n, e->n);
      break;
    case NAV_EVENT_TREE_REACHED:
      n = appendQuantity(out, size, n, "s_t ", e->a, 3, " ");
      n = appendFixed(out, size, n, e->b, 3);
      break;
    case NAV_EVENT_RECOVERY:
    case NAV_EVENT_APPROACH_BY_MEMORY:
      if (e->variant) {
        n = appendQuantity(out, size, n, "e_d ", e->a, 2, " m");
      } else {
        n = append(out, size, n, "not seen ");
        n = appendInt(out, size, n, e->n);
        n = append(out, size, n, " ms");
      }
      break;
    case NAV_EVENT_WAYPOINT:
      n = appendInt(out, size, n, e->n);
      break;
    case NAV_EVENT_LINK_LOST:
      n = e->variant ? appendQuantity(out, size, n, "camera silent ", e->a, 1, " s: landing")
                     : append(out, size, n, "camera silent: holding position");
      break;
    case NAV_EVENT_LINK_RESTORED:
      n = appendQuantity(out, size, n, "after ", e->a, 1, " s");
      break;
    default:
      break;
  }
  return (int)n;
}

int navFormatEvent(const NavEvent* e, char* out, size_t size) {
  char detail[64];
  navFormatEventDetail(e, detail, sizeof(detail));
  size_t n = 0;
  out[0] = '\0';
  if (e->kind == NAV_EVENT_PHASE) {
    n = append(out, size, n, "phase ");
    return (int)append(out, size, n, detail);
  }
  n = append(out, size, n, navEventKindName(e->kind));
  if (e->tree_id) {
    n = append(out, size, n, " tree ");
    n = appendInt(out, size, n, e->tree_id);
  }
  const bool positioned = e->kind == NAV_EVENT_TREE_ADDED || e->kind == NAV_EVENT_TREE_REACHED ||
                          e->kind == NAV_EVENT_TARGET_SELECTED || e->kind == NAV_EVENT_RECOVERY ||
                          e->kind == NAV_EVENT_ABANDONED || e->kind == NAV_EVENT_APPROACH_BY_MEMORY ||
                          e->kind == NAV_EVENT_REVISIT;
  if (positioned) {
    n = appendQuantity(out, size, n, " at (", e->x, 3, ", ");
    n = appendQuantity(out, size, n, "", e->y, 3, ")");
  }
  if (detail[0] != '\0') {
    n = append(out, size, n, " ");
    n = append(out, size, n, detail);
  }
  return (int)n;
}
