/*
 * The camera's serial lines on the flight controller (the port of jevois_module/ForaNavTrees/foranav_serial.py,
 * parse side, and of NavigationApp.on_camera_line / _end_frame in crazyflie_app/app/navigation.py).
 *
 *   T2 x y               one detected tree, standardized coordinates (centre 0 0, x -1000..1000, y -750..750)
 *   N2 id x y w h        one detected tree with a species label and box size
 *   MARK START / STOP    frame delimiters; anything else (OK, ERR ..., ALIVE, noise) is ignored
 *
 * Any of CR, LF, NUL ends a line; a line longer than NAV_MAX_LINE_LENGTH is dropped whole, so the buffer is
 * bounded whatever arrives. Numbers follow Python's float() grammar (digits with single underscores, one
 * optional point, optional exponent); non-finite values and coordinates outside the frame are rejected.
 */
#include <math.h>
#include <string.h>
#ifndef NAV_NO_STRTOD
#include <stdlib.h>
#endif

#include "nav_core.h"

#define STD_HALF_WIDTH 1000.0
#define STD_HALF_HEIGHT 750.0
#define MAX_TOKENS 7

void navLineAssemblerInit(NavLineAssembler* assembler) { memset(assembler, 0, sizeof(*assembler)); }

bool navLineAssemblerPush(NavLineAssembler* a, uint8_t byte, const char** line, int32_t* length) {
  if (byte == 10 || byte == 13 || byte == 0) { /* LF, CR, NUL end a line */
    const bool complete = !a->overlong && a->length > 0;
    if (a->overlong) {
      a->dropped++;
    }
    a->buf[a->length] = '\0';
    *line = a->buf;
    *length = a->length;
    a->length = 0;
    a->overlong = false;
    return complete;
  }
  if (!a->overlong) {
    a->buf[a->length++] = (char)byte;
    if (a->length > NAV_MAX_LINE_LENGTH) {
      a->overlong = true;
      a->length = 0;
    }
  }
  return false;
}

static bool isSpace(char c) { /* str.split() whitespace within ASCII */
  return c == ' ' || (c >= 9 && c <= 13) || (c >= 0x1c && c <= 0x1f);
}

static bool isDigit(char c) { return c >= '0' && c <= '9'; }

/* digitpart = digit (["_"] digit)*; returns the index after it, copying digits to out. */
static int32_t digitPart(const char* s, int32_t i, int32_t end, char* out, int32_t* n) {
  if (i >= end || !isDigit(s[i])) {
    return -1;
  }
  out[(*n)++] = s[i++];
  while (i < end) {
    if (isDigit(s[i])) {
      out[(*n)++] = s[i++];
    } else if (s[i] == '_' && i + 1 < end && isDigit(s[i + 1])) {
      i++;
    } else {
      break;
    }
  }
  return i;
}

/* A cleaned decimal ([sign] digits [. digits] [e [sign] digits]) to double. Mantissas below 2^53 with
 * a decimal exponent within +-22 (every number the camera sends) take Clinger's exact path: one product or
 * quotient of two exact doubles, correctly rounded like Python's float(). Others go to strtod on the host;
 * the Bolt build (NAV_NO_STRTOD: newlib's strtod needs malloc) scales step by step, within a few ulp. */
static double decimalToDouble(const char* s) {
  static const double POW10[] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11,
                                 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const char* p = s;
  const bool negative = *p == '-';
  if (*p == '+' || *p == '-') {
    p++;
  }
  uint64_t mantissa = 0;
  int digits = 0, exponent = 0;
  bool exact = true;
  for (; isDigit(*p) || *p == '.'; p++) {
    if (*p == '.') {
      continue;
    }
    if (mantissa == 0 && *p == '0') {
      /* leading zeros carry no digits */
    } else if (digits < 19) {
      mantissa = mantissa * 10u + (uint64_t)(*p - '0');
      digits++;
    } else {
      exponent++; /* digits past 19 only scale */
      exact = exact && *p == '0';
    }
  }
  for (const char* q = s; *q != '\0' && *q != 'e' && *q != 'E'; q++) {
    if (*q == '.') {
      for (const char* r = q + 1; isDigit(*r); r++) {
        exponent--;
      }
      break;
    }
  }
  if (*p == 'e' || *p == 'E') {
    p++;
    const bool negative_exponent = *p == '-';
    if (*p == '+' || *p == '-') {
      p++;
    }
    int e = 0;
    for (; isDigit(*p); p++) {
      e = e < 100000 ? e * 10 + (*p - '0') : e;
    }
    exponent += negative_exponent ? -e : e;
  }
  double value;
  if (mantissa == 0) {
    value = 0.0;
  } else if (exact && mantissa < ((uint64_t)1 << 53) && exponent >= -22 && exponent <= 22) {
    value = exponent >= 0 ? (double)mantissa * POW10[exponent] : (double)mantissa / POW10[-exponent];
  } else {
#ifndef NAV_NO_STRTOD
    return strtod(s, NULL);
#else
    value = (double)mantissa;
    for (; exponent > 0; exponent--) {
      value *= 10.0;
    }
    for (; exponent < 0; exponent++) {
      value /= 10.0;
    }
#endif
  }
  return negative ? -value : value;
}

/* Python float(token) for a finite decimal number; false for anything else. */
static bool parseNumber(const char* s, int32_t length, double* value) {
  char clean[NAV_MAX_LINE_LENGTH + 2];
  int32_t n = 0, i = 0;
  if (i < length && (s[i] == '+' || s[i] == '-')) {
    clean[n++] = s[i++];
  }
  bool digits = false;
  if (i < length && isDigit(s[i])) {
    i = digitPart(s, i, length, clean, &n);
    digits = true;
  }
  if (i < length && s[i] == '.') {
    clean[n++] = s[i++];
    if (i < length && isDigit(s[i])) {
      i = digitPart(s, i, length, clean, &n);
      digits = true;
    }
  }
  if (!digits) {
    return false; /* also inf, infinity, nan: never finite coordinates */
  }
  if (i < length && (s[i] == 'e' || s[i] == 'E')) {
    clean[n++] = s[i++];
    if (i < length && (s[i] == '+' || s[i] == '-')) {
      clean[n++] = s[i++];
    }
    i = digitPart(s, i, length, clean, &n);
    if (i < 0) {
      return false;
    }
  }
  if (i != length) {
    return false;
  }
  clean[n] = '\0';
  *value = decimalToDouble(clean);
  return isfinite(*value);
}

static bool inFrame(double x, double y) { return fabs(x) <= STD_HALF_WIDTH && fabs(y) <= STD_HALF_HEIGHT; }

static bool tokenIs(const char* s, int32_t length, const char* word) {
  return (size_t)length == strlen(word) && memcmp(s, word, (size_t)length) == 0;
}

NavMessage navParseLine(const char* line, int32_t length) {
  NavMessage m;
  memset(&m, 0, sizeof(m));
  m.kind = NAV_LINE_NONE;
  if (length > NAV_MAX_LINE_LENGTH + 2) {
    return m;
  }
  const char* start[MAX_TOKENS];
  int32_t size[MAX_TOKENS];
  int32_t tokens = 0;
  for (int32_t i = 0; i < length; i++) {
    if ((unsigned char)line[i] >= 0x80) {
      return m; /* not ASCII */
    }
  }
  for (int32_t i = 0; i < length;) {
    while (i < length && isSpace(line[i])) {
      i++;
    }
    if (i >= length) {
      break;
    }
    if (tokens == MAX_TOKENS) {
      return m; /* more tokens than any message has */
    }
    start[tokens] = line + i;
    while (i < length && !isSpace(line[i])) {
      i++;
    }
    size[tokens] = (int32_t)(line + i - start[tokens]);
    tokens++;
  }
  if (tokens == 0) {
    return m;
  }
  double v[4];
  if (tokenIs(start[0], size[0], "T2") && tokens == 3) {
    if (parseNumber(start[1], size[1], &v[0]) && parseNumber(start[2], size[2], &v[1]) && inFrame(v[0], v[1])) {
      m.kind = NAV_LINE_T2;
      m.x = v[0];
      m.y = v[1];
    }
    return m;
  }
  if (tokenIs(start[0], size[0], "N2") && tokens == 6) {
    for (int32_t k = 0; k < 4; k++) {
      if (!parseNumber(start[2 + k], size[2 + k], &v[k])) {
        return m;
      }
    }
    if (inFrame(v[0], v[1]) && v[2] >= 0.0 && v[2] <= 2 * STD_HALF_WIDTH && v[3] >= 0.0 &&
        v[3] <= 2 * STD_HALF_HEIGHT) {
      m.kind = NAV_LINE_N2;
      memcpy(m.label, start[1], (size_t)size[1]);
      m.label[size[1]] = '\0';
      m.x = v[0];
      m.y = v[1];
      m.w = v[2];
      m.h = v[3];
    }
    return m;
  }
  if (tokenIs(start[0], size[0], "MARK") && tokens == 2) {
    if (tokenIs(start[1], size[1], "START")) {
      m.kind = NAV_LINE_MARK_START;
    } else if (tokenIs(start[1], size[1], "STOP")) {
      m.kind = NAV_LINE_MARK_STOP;
    }
  }
  return m;
}

double navStdToImgX(double x, int32_t width) { return (x + 1000.0) * (double)width / 2000.0; }

double navStdToImgY(double y, int32_t height) { return (y / 0.75 + 1000.0) * (double)height / 2000.0; }

/* -- frames ---------------------------------------------------------------------------------------------- */

void navCameraInputInit(NavCameraInput* input, const char* target_label) {
  memset(input, 0, sizeof(*input));
  navLineAssemblerInit(&input->assembler);
  if (target_label != NULL) {
    strncpy(input->target_label, target_label, sizeof(input->target_label) - 1);
  }
}

static bool endFrame(NavCameraInput* input, NavCore* core, int32_t t_ms, const NavPose* pose_now, bool pose_valid) {
  if (input->frame_length == 0 || core->phase == NAV_PHASE_DONE || core->phase == NAV_PHASE_NO_CAMERA ||
      !pose_valid) {
    input->frame_length = 0;
    return false;
  }
  memcpy(input->last_frame, input->frame, (size_t)input->frame_length * sizeof(NavDetection));
  input->last_frame_length = input->frame_length;
  input->frame_length = 0;
  navCoreOnFrame(core, t_ms, input->last_frame, input->last_frame_length, pose_now);
  input->frames++;
  return true;
}

static bool onLine(NavCameraInput* input, NavCore* core, const char* line, int32_t length, int32_t t_ms,
                   const NavPose* pose_now, bool pose_valid) {
  const NavMessage m = navParseLine(line, length);
  if (m.kind != NAV_LINE_NONE) {
    input->heard = true;
    input->last_heard_ms = t_ms;
  }
  if (m.kind == NAV_LINE_MARK_START || m.kind == NAV_LINE_MARK_STOP) {
    input->marks_seen = true;
    navCoreOnFrameMark(core, t_ms);
    return endFrame(input, core, t_ms, pose_now, pose_valid);
  }
  if (m.kind == NAV_LINE_T2 || m.kind == NAV_LINE_N2) {
    if (m.kind == NAV_LINE_N2 && input->target_label[0] != '\0' && strcmp(m.label, input->target_label) != 0) {
      input->other_labels++;
      return false;
    }
    const int32_t capacity = core->params.frame_capacity < NAV_MAX_FRAME_DETECTIONS ? core->params.frame_capacity
                                                                                       : NAV_MAX_FRAME_DETECTIONS;
    if (input->frame_length >= capacity) {
      input->frame_overflow++; /* T2 lines without MARK STOP must not pile up without limit */
      return false;
    }
    NavDetection* d = &input->frame[input->frame_length++];
    d->u = navStdToImgX(m.x, core->params.cam_width_px);
    d->v = navStdToImgY(m.y, core->params.cam_height_px);
  }
  return false;
}

size_t navCameraInputFeed(NavCameraInput* input, NavCore* core, const uint8_t* data, size_t length, int32_t t_ms,
                          const NavPose* pose_now, bool pose_valid, bool* frame_done) {
  *frame_done = false;
  for (size_t i = 0; i < length; i++) {
    const char* line;
    int32_t line_length;
    if (navLineAssemblerPush(&input->assembler, data[i], &line, &line_length) &&
        onLine(input, core, line, line_length, t_ms, pose_now, pose_valid)) {
      *frame_done = true;
      return i + 1;
    }
  }
  return length;
}

bool navCameraInputEndBatch(NavCameraInput* input, NavCore* core, int32_t t_ms, const NavPose* pose_now,
                            bool pose_valid) {
  if (input->frame_length > 0 && !input->marks_seen) {
    return endFrame(input, core, t_ms, pose_now, pose_valid);
  }
  return false;
}

bool navCameraInputAlive(const NavCameraInput* input, const NavParams* params, int32_t t_ms) {
  if (params->camera_wait_ms <= 0) {
    return true;
  }
  return input->heard && t_ms - input->last_heard_ms <= params->link_hold_ms;
}
