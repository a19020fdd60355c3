"""Flown path (ground truth in the drone's tlog, 10 Hz) against what the example asked."""
import math, os, re, sys
os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil

def truth(path):
    m = mavutil.mavlink_connection(path, dialect="common")
    pts, texts = [], []
    while (msg := m.recv_match(type=["DEBUG_VECT", "STATUSTEXT"])) is not None:
        if msg.get_type() == "STATUSTEXT": texts.append(msg.text)
        elif msg.name == "gt_pos": pts.append((msg.x, -msg.y, -msg.z))
    return pts, texts

def sequence(tlog):
    pts, texts = truth(tlog)
    seq = [(0.0, 0.0, 0.4), (0.0, 0.0, 1.2), (0.5, -0.5, 1.2), (0.5, 0.5, 1.2), (-0.5, 0.5, 1.2), (-0.5, -0.5, 1.2),
           (0.0, 0.0, 1.2), (0.0, 0.0, 0.4)]
    i, errs = next(k for k, p in enumerate(pts) if p[2] > 0.05), []
    for wp in seq:  # in order: the closest the path came to each waypoint after reaching the previous one
        best, best_j = 1e9, i
        for j in range(i, len(pts)):
            d = math.dist(pts[j], wp)
            if d < best: best, best_j = d, j
            if j > best_j + 60: break  # 6 s after the best: the next hold
        errs.append(best); i = best_j
    return errs, texts

def figure8(tlog, example):
    src = open(example).read()
    rows = eval(re.search(r"figure8 = (\[.*?\n\])", src, re.S).group(1))
    curve, t = [], 0.0
    for row in rows:
        d = row[0]
        for k in range(50):
            s = d * k / 50
            curve.append(tuple(sum(c * s ** n for n, c in enumerate(row[1 + 8 * a:9 + 8 * a])) for a in range(3)))
    pts, texts = truth(tlog)
    air = [p for p in pts if p[2] > 0.9]
    x0, y0 = air[0][0], air[0][1]
    moving = [p for p in air if math.hypot(p[0] - x0, p[1] - y0) > 0.05]
    errs = [min(math.dist(p, (x0 + c[0], y0 + c[1], 1.0 + c[2])) for c in curve) for p in moving]
    return errs, texts

kind, tlog = sys.argv[1], sys.argv[2]
errs, texts = sequence(tlog) if kind == "sequence" else figure8(tlog, sys.argv[3])
errs = sorted(errs)
print("%s: n=%d mean %.3f m, max %.3f m; console: %s" % (kind, len(errs), sum(errs) / len(errs), errs[-1], texts))
