#!/usr/bin/env python3
"""How much of the RPE against a CARMEN log's reference poses is the
reference's own error: a three-cornered hat over the RPE pairs.

The reference poses of the corpus (the "corrected" logs) were themselves
made by scan matching; they have errors of their own. For every RPE pair
(scan i and scan j, the first 2 m of reference path later; the pairs of
`carenav eval --rpe-dist 2`) three estimates of the relative pose are
compared: the reference's, the trajectory's under test, and a third one
made from the two scans alone (trimmed point-to-point ICP of scan j onto
scan i, started at the reference's relative pose, pairs within 0.2 m; a
pair is used when at least half of scan j's points pair). If their errors
are independent, the three mean squared differences give each one's own
mean squared error (the three-cornered hat of clock comparison, [Gray74]):

    s_ref^2  = (d(ref, icp)^2 + d(ref, est)^2 - d(est, icp)^2) / 2
    s_est^2  = (d(est, icp)^2 + d(ref, est)^2 - d(ref, icp)^2) / 2
    s_icp^2  = (d(ref, icp)^2 + d(est, icp)^2 - d(ref, est)^2) / 2

(d: root mean square of the difference of the translations, m; pairs where
any difference exceeds 0.3 m are left out as a failed pairwise ICP). The
errors are not fully independent (all three come from the same scans), so
read the split as an estimate: it says whether an RPE against the
reference can go below the reference's own error, not the exact floor.

Needs numpy and scipy (Debian: python3-numpy python3-scipy).

  tests/bench/slam_reference_noise.py tests/data/carmen/edmonton-corrected.log.gz \\
      OUT/rawlog/edmonton-laser.tum OUT/slam/edmonton-odo1/trajectory.tum [more trajectories]

(OUT: a `tests/bench/slam_corpus.py` output; its rawlog/LOG-laser.tum is
the reference, one pose per scan, robot frame.)
"""
import argparse
import gzip
import math

import numpy as np
from scipy.spatial import cKDTree

PAIR_PATH = 2.0  # m of reference path, as `slam_corpus.py`'s RPE
PAIR_DIST = 0.2  # m, ICP pairing distance
MIN_PAIRED = 0.5  # share of scan j's points paired for a usable pair
MAX_DIFF = 0.3  # m, a larger difference is a failed pairwise ICP


def old_laser_increment(n):
    """Beam spacing of a CARMEN FLASER message, as `carenav import carmen`."""
    if n in (180, 181):
        return math.pi / 180
    if n in (360, 361):
        return math.pi / 360
    if n in (400, 401):
        return math.pi / 720
    return math.pi / (n - 1) if n > 1 else 0


def read_scans(log):
    """The FLASER scans of a CARMEN log as points in the robot's frame.
    Readings under 5 cm are dropped, and so are those within 1 cm of the
    log's largest reading: a scanner writes a beam that hit nothing as one
    value at the top of its readings (50-82 m in the corpus logs)."""
    offset, ranges = 0.0, []
    with gzip.open(log, "rt") if log.endswith(".gz") else open(log) as f:
        for line in f:
            w = line.split()
            if len(w) >= 3 and w[0] == "PARAM" and w[1] == "robot_frontlaser_offset":
                offset = float(w[2])
            if w and w[0] == "FLASER":
                ranges.append(np.array([float(v) for v in w[2:2 + int(w[1])]]))
    top = max((r.max() for r in ranges if len(r)), default=0.0)
    scans = []
    for r in ranges:
        a = -math.pi / 2 + old_laser_increment(len(r)) * np.arange(len(r))
        ok = (r > 0.05) & (r < top - 0.01)
        scans.append(np.c_[offset + r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok])])
    return scans


def read_tum(path):
    """x, y, yaw arrays of a TUM file."""
    rows = [[float(v) for v in l.split()] for l in open(path)
            if l.strip() and not l.startswith("#")]
    a = np.array(rows)
    return a[:, 1], a[:, 2], 2 * np.arctan2(a[:, 6], a[:, 7])


def relative(traj, i, j):
    """Pose j in the frame of pose i: x, y, yaw."""
    x, y, t = traj
    c, s = math.cos(t[i]), math.sin(t[i])
    dx, dy = x[j] - x[i], y[j] - y[i]
    return c * dx + s * dy, -s * dx + c * dy, t[j] - t[i]


def pair_icp(tree, ref_pts, pts, start, iterations=40):
    """Trimmed point-to-point ICP of `pts` onto the tree's points from
    `start`; (x, y, yaw, share paired) or None."""
    x, y, t = start
    share = 0.0
    for _ in range(iterations):
        c, s = math.cos(t), math.sin(t)
        p = pts @ np.array([[c, s], [-s, c]]) + [x, y]
        d, k = tree.query(p)
        m = d < PAIR_DIST
        share = m.mean() if len(m) else 0.0
        if m.sum() < 30:
            return None
        p, q = p[m], ref_pts[k[m]]
        mp, mq = p.mean(0), q.mean(0)
        h = (p - mp).T @ (q - mq)
        a = math.atan2(h[0, 1] - h[1, 0], h[0, 0] + h[1, 1])
        ca, sa = math.cos(a), math.sin(a)
        rot = np.array([[ca, -sa], [sa, ca]])
        shift = mq - rot @ mp
        x, y = rot @ [x, y] + shift
        t += a
        if abs(a) < 1e-6 and np.hypot(*shift) < 1e-5:
            break
    return x, y, t, share


def rpe_pairs(ref):
    """(i, j): j the first scan PAIR_PATH m of reference path after i."""
    x, y, _ = ref
    s = np.concatenate([[0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    j, out = 0, []
    for i in range(len(x) - 1):
        j = max(j, i + 1)
        while j < len(x) and s[j] - s[i] < PAIR_PATH:
            j += 1
        if j == len(x):
            break
        out.append((i, j))
    return out


def revisit_pairs(ref, min_path=10.0, max_dist=1.5, max_turn=45.0, stride=1):
    """(i, j): scan j revisits the place of scan i, at least `min_path` m of
    reference path later, within `max_dist` m and `max_turn` deg (by the
    reference); for each i the closest such j. Places revisited after a
    long way test a trajectory's consistency beyond 2 m."""
    x, y, t = ref
    s = np.concatenate([[0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    out = []
    for i in range(0, len(x), stride):
        later = np.nonzero(s - s[i] >= min_path)[0]
        if len(later) == 0:
            break
        d = np.hypot(x[later] - x[i], y[later] - y[i])
        turn = np.degrees(np.abs(np.angle(np.exp(1j * (t[later] - t[i])))))
        ok = (d <= max_dist) & (turn <= max_turn)
        if ok.any():
            out.append((i, int(later[ok][np.argmin(d[ok])])))
    return out


def hat(ref_icp, est_icp, ref_est):
    """Each one's own rms error from the three rms differences (signed: a
    negative square says the independence assumption fails)."""
    a, b, c = ref_icp ** 2, est_icp ** 2, ref_est ** 2
    root = lambda v: math.copysign(math.sqrt(abs(v)), v)
    return root((a + c - b) / 2), root((b + c - a) / 2), root((a + b - c) / 2)


def split_errors(log, ref_path, est_paths, revisits=False):
    """The three-cornered hat of every trajectory in `est_paths` against the
    reference and the pairwise ICP. Returns (pairs, pairs with an ICP,
    rows); a row per trajectory: pairs used, the three rms differences
    (ref-icp, est-icp, ref-est) and the three own errors (s_ref, s_est,
    s_icp), m. Raises ValueError for unreadable or mismatched files."""
    try:
        scans, ref = read_scans(log), read_tum(ref_path)
        ests = [read_tum(p) for p in est_paths]
    except (OSError, IndexError) as e:
        raise ValueError(str(e)) from e
    n = min([len(scans), len(ref[0])] + [len(e[0]) for e in ests])
    if n != len(ref[0]) or any(len(e[0]) != n for e in ests):
        raise ValueError(f"{ref_path}: every trajectory needs one pose per scan ({len(scans)} scans)")
    pairs = revisit_pairs(ref) if revisits else rpe_pairs(ref)
    diffs = []  # per usable pair: the translation of ref and of each est minus icp's
    for i, j in pairs:
        tree = cKDTree(scans[i])
        icp = pair_icp(tree, scans[i], scans[j], relative(ref, i, j))
        if icp is None or icp[3] < MIN_PAIRED:
            continue
        diffs.append([np.subtract(relative(t, i, j)[:2], icp[:2]) for t in [ref] + ests])
    d = np.array(diffs)
    rows = []
    for k in range(1, len(est_paths) + 1 if len(d) else 1):
        ri = (d[:, 0] ** 2).sum(-1)
        ei = (d[:, k] ** 2).sum(-1)
        re = ((d[:, 0] - d[:, k]) ** 2).sum(-1)
        ok = (ri < MAX_DIFF ** 2) & (ei < MAX_DIFF ** 2) & (re < MAX_DIFF ** 2)
        rms = [math.sqrt(v[ok].mean()) for v in (ri, ei, re)] if ok.any() else [math.nan] * 3
        rows.append({"pairs": int(ok.sum()), "rms": rms, "own": list(hat(*rms))})
    return len(pairs), len(d), rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("log", help="CARMEN log (FLASER messages)")
    ap.add_argument("ref", help="reference poses, TUM, one per FLASER scan")
    ap.add_argument("est", nargs="+", help="trajectories under test, TUM, one pose per scan")
    ap.add_argument("--revisits", action="store_true",
                    help="pairs that revisit a place at least 10 m of path later (within 1.5 m\n"
                         "and 45 deg by the reference) instead of the RPE pairs")
    a = ap.parse_args()
    try:
        n_pairs, n_icp, rows = split_errors(a.log, a.ref, a.est, a.revisits)
    except ValueError as e:
        raise SystemExit(f"slam_reference_noise: {e}")
    kind = "revisit" if a.revisits else "RPE"
    print(f"{a.log}: {n_pairs} {kind} pairs, {n_icp} with a pairwise ICP")
    if not rows:
        return
    print("| trajectory | pairs | d(ref, icp) | d(est, icp) | d(ref, est) | s_ref | s_est | s_icp |")
    print("|---|---|---|---|---|---|---|---|")
    for name, r in zip(a.est, rows):
        print(f"| {name} | {r['pairs']} | " + " | ".join(f"{v:.3f}" for v in r["rms"] + r["own"]) + " |")


if __name__ == "__main__":
    main()
