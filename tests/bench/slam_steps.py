#!/usr/bin/env python3
"""Where a SLAM trajectory went wrong: the steps whose motion differs most
from the reference's, paired by index (one pose per scan, as
`carenav import carmen` and `carenav slam` write them).

For every scan i the motion from scan i-1 to i is taken in the frame of
scan i-1 for both trajectories; the error is their difference (m, and deg
of heading). ATE tells how far a map is off; this tells at which scans it
went off, and how (a step behind, sideways, turned).

  tests/bench/slam_steps.py OUT/slam/csail-laser/trajectory.tum OUT/rawlog/csail-laser.tum [--worst 15]
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from slam_corpus import tum_rows  # noqa: E402


def poses(path):
    """(x, y, yaw) of each TUM row (yaw from the quaternion's z and w)."""
    return [(r[1], r[2], 2 * math.atan2(r[6], r[7])) for r in tum_rows(path)]


def step(a, b):
    """The motion from pose a to pose b in a's frame: forward, left, turn."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    c, s = math.cos(a[2]), math.sin(a[2])
    return c * dx + s * dy, -s * dx + c * dy, math.remainder(b[2] - a[2], 2 * math.pi)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("est")
    ap.add_argument("ref")
    ap.add_argument("--worst", type=int, default=15, help="how many steps to list")
    a = ap.parse_args()
    est, ref = poses(a.est), poses(a.ref)
    if len(est) != len(ref):
        print(f"{a.est}: {len(est)} poses, {a.ref}: {len(ref)}: not one pose per scan each",
              file=sys.stderr)
        sys.exit(2)
    rows = []
    for i in range(1, len(est)):
        e, r = step(est[i - 1], est[i]), step(ref[i - 1], ref[i])
        err = math.hypot(e[0] - r[0], e[1] - r[1])
        turn = math.degrees(math.remainder(e[2] - r[2], 2 * math.pi))
        rows.append((err + 0.02 * abs(turn), i, err, turn, e, r))
    bad = sum(1 for x in rows if x[2] > 0.1 or abs(x[3]) > 2)
    print(f"{len(est)} poses; {bad} steps off by more than 0.1 m or 2 deg")
    print("| scan | error (m) | heading error (deg) | est step fwd, left (m), turn (deg) | ref step |")
    print("|---|---|---|---|---|")
    for _, i, err, turn, e, r in sorted(rows, reverse=True)[: a.worst]:
        print(f"| {i} | {err:.3f} | {turn:+.2f} | {e[0]:+.2f}, {e[1]:+.2f}, {math.degrees(e[2]):+.1f} "
              f"| {r[0]:+.2f}, {r[1]:+.2f}, {math.degrees(r[2]):+.1f} |")


if __name__ == "__main__":
    main()
