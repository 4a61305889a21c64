#!/usr/bin/env python3
"""Writes a seeded benchmark of cluttered carenav worlds and goal scenarios.

Each world is a 12.5 m x 5 m room (0.05 m per pixel PGM, walls all round)
with a field of 0.15 m posts (cylinders of the lidar's height, drawn as 3 x 3
cells) between x = 2.5 m and x = 9.5 m; the robot starts at (1, 2.5) facing
+x and is sent to (11, 2.5): a 10 m run through the field. Worlds are graded
by difficulty (the number of posts grows with it); every world has a way
through for the robot (its width plus `--margin`, default 10 cm, measured
on the posts' squares), and the narrowest gap along the widest way is
written to the manifest.

The robot (`robot.ini`): a 0.51 m x 0.43 m differential base, a 270 deg
lidar of 720 beams at 10 Hz, 2.0 m/s and 4.0 rad/s at most, reversing at up
to 0.5 m/s (the runner
lowers the limits with --set). A run fails on a collision or after 100 s.

  python3 tests/bench/clutter/make_clutter.py --n 100 --seed 1 --out /tmp/clutter1

writes OUT/robot.ini, OUT/worlds/clutter_NNN.{pgm,yaml},
OUT/scenarios/clutter_NNN.yaml and OUT/manifest.csv (world, difficulty,
posts, narrowest gap on the widest way in m). Standard library only; the
same seed gives the same files.
"""
import argparse
import heapq
import math
import os
import random

RES = 0.05
W, H = 12.5, 5.0  # room (m)
WALL = 0.1  # wall thickness (m)
FIELD = (2.5, 9.5)  # x range of the post field (m)
POST = 0.15  # post side (m)
START = (1.0, 2.5)
GOAL = (11.0, 2.5)
ROBOT_LEN, ROBOT_WID = 0.51, 0.43

ROBOT_INI = """; Benchmark robot of tests/bench/clutter (written by make_clutter.py):
; a 0.51 m x 0.43 m differential base with a 270 deg lidar, 2 m/s and 4 rad/s, reversing at 0.5 m/s.
[profile]
name = clutter-robot
description = clutter benchmark robot: 0.51 x 0.43 m differential base, 270 deg lidar
base = {base}

[robot]
footprint = 0.255,0.215 -0.255,0.215 -0.255,-0.215 0.255,-0.215
height = 0.5
v_max = 2.0
v_min = -0.5
w_max = 4.0
acc_v = 2.0
acc_w = 4.0
safe_distance = 0.1

[sensor.laser]
type = lidar2d
x = 0.12
y = 0
z = 0.3
yaw = 0
rate_hz = 10
fov = 270
beams = 720
range_min = 0.1
range_max = 30
noise_std = 0.01

[navigation]
plugin = goal-dwa
goal_tolerance = 0.3
goal_tolerance_deg = 180
"""


def square_dist(px, py, cx, cy, half):
    """Distance from (px, py) to the axis-aligned square of half side `half`."""
    dx = max(abs(px - cx) - half, 0.0)
    dy = max(abs(py - cy) - half, 0.0)
    return math.hypot(dx, dy)


def clearance_grid(posts, nx, ny, cap=0.6):
    """Per cell (centre), the distance to the nearest post square or wall, capped."""
    g = [[cap] * nx for _ in range(ny)]
    for iy in range(ny):
        y = (iy + 0.5) * RES
        dwall_y = min(y - WALL, H - WALL - y)
        row = g[iy]
        for ix in range(nx):
            x = (ix + 0.5) * RES
            row[ix] = max(0.0, min(cap, dwall_y, x - WALL, W - WALL - x))
    r = int(math.ceil(cap / RES)) + 2
    for (cx, cy) in posts:
        ix0, iy0 = int(cx / RES), int(cy / RES)
        for iy in range(max(0, iy0 - r), min(ny, iy0 + r + 1)):
            y = (iy + 0.5) * RES
            row = g[iy]
            for ix in range(max(0, ix0 - r), min(nx, ix0 + r + 1)):
                d = square_dist((ix + 0.5) * RES, y, cx, cy, POST / 2)
                if d < row[ix]:
                    row[ix] = d
    return g


def widest_way(g, nx, ny, start, goal):
    """Bottleneck clearance of the widest 8-connected way from start to goal."""
    s = (int(start[1] / RES), int(start[0] / RES))
    t = (int(goal[1] / RES), int(goal[0] / RES))
    best = [[-1.0] * nx for _ in range(ny)]
    best[s[0]][s[1]] = g[s[0]][s[1]]
    heap = [(-best[s[0]][s[1]], s)]
    while heap:
        negc, (iy, ix) = heapq.heappop(heap)
        c = -negc
        if c < best[iy][ix]:
            continue
        if (iy, ix) == t:
            return c
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                jy, jx = iy + dy, ix + dx
                if (dy or dx) and 0 <= jy < ny and 0 <= jx < nx:
                    cc = min(c, g[jy][jx])
                    if cc > best[jy][jx]:
                        best[jy][jx] = cc
                        heapq.heappush(heap, (-cc, (jy, jx)))
    return 0.0


def make_world(rng, difficulty, need):
    """Posts for one world: as many as the difficulty asks for, placed at
    random (not overlapping, clear of start and goal), dropping the last
    placed posts until the widest way's bottleneck clearance is >= need."""
    nx, ny = int(round(W / RES)), int(round(H / RES))
    area = (FIELD[1] - FIELD[0]) * (H - 2 * WALL)
    count = int(round(area * (0.8 + 3.2 * difficulty)))  # posts per m^2: 0.8 .. 4.0
    posts = []
    tries = 0
    while len(posts) < count and tries < count * 50:
        tries += 1
        # post centres on cell centres: the post is exactly 3 x 3 cells
        cx = (int(rng.uniform(FIELD[0], FIELD[1]) / RES) + 0.5) * RES
        cy = (int(rng.uniform(WALL + POST / 2, H - WALL - POST / 2) / RES) + 0.5) * RES
        if any(abs(cx - px) < POST + 1e-6 and abs(cy - py) < POST + 1e-6 for px, py in posts):
            continue
        if math.hypot(cx - START[0], cy - START[1]) < 1.0 or math.hypot(cx - GOAL[0], cy - GOAL[1]) < 1.0:
            continue
        posts.append((cx, cy))
    while True:
        g = clearance_grid(posts, nx, ny)
        c = widest_way(g, nx, ny, START, GOAL)
        if c >= need or not posts:
            return posts, c
        # drop a tenth of the posts (the most recently placed) and try again
        posts = posts[: max(0, len(posts) - max(1, len(posts) // 10))]


def write_pgm(path, posts):
    nx, ny = int(round(W / RES)), int(round(H / RES))
    px = [[254] * nx for _ in range(ny)]  # row 0 = top (y max)
    wall_cells = int(round(WALL / RES))
    for r in range(ny):
        for c in range(nx):
            if r < wall_cells or r >= ny - wall_cells or c < wall_cells or c >= nx - wall_cells:
                px[r][c] = 0
    for (cx, cy) in posts:
        ix, iy = int(cx / RES), int(cy / RES)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                r = ny - 1 - (iy + dy)
                px[r][ix + dx] = 0
    with open(path, "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (nx, ny))
        for row in px:
            f.write(bytes(row))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=30, help="number of worlds (default 30)")
    ap.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--margin", type=float, default=0.10,
                    help="m, the widest way is at least the robot's width plus this (default 0.10)")
    ap.add_argument("--duration", type=float, default=100, help="s, time limit of a run (default 100)")
    a = ap.parse_args()
    if a.n < 1 or a.n > 10000:
        ap.error("--n must be in 1..10000")
    rng = random.Random(a.seed)
    os.makedirs(os.path.join(a.out, "worlds"), exist_ok=True)
    os.makedirs(os.path.join(a.out, "scenarios"), exist_ok=True)
    here = os.path.dirname(os.path.abspath(__file__))
    base = os.path.relpath(os.path.join(here, "..", "..", "..", "ini", "defaults.ini"), os.path.abspath(a.out))
    with open(os.path.join(a.out, "robot.ini"), "w") as f:
        f.write(ROBOT_INI.format(base=base))
    need = (ROBOT_WID + a.margin) / 2
    rows = []
    for i in range(a.n):
        difficulty = i / max(1, a.n - 1)  # graded: easy to hard
        posts, c = make_world(rng, difficulty, need)
        name = "clutter_%03d" % i
        write_pgm(os.path.join(a.out, "worlds", name + ".pgm"), posts)
        with open(os.path.join(a.out, "worlds", name + ".yaml"), "w") as f:
            f.write("# carenav world (docs/simulate.md), written by tests/bench/clutter/make_clutter.py\n"
                    "# --seed %d, world %d: %d posts of %.2f m, difficulty %.2f, narrowest gap on the\n"
                    "# widest way %.2f m.\n" % (a.seed, i, len(posts), POST, difficulty, 2 * c))
            f.write("format: 1\nname: %s\nmap: %s.pgm\nresolution: %g\norigin: [0, 0]\n" % (name, name, RES))
        with open(os.path.join(a.out, "scenarios", name + ".yaml"), "w") as f:
            f.write("# carenav scenario (docs/navigate.md), written by tests/bench/clutter/make_clutter.py\n")
            f.write("format: 1\nworld: ../worlds/%s.yaml\nprofile: ../robot.ini\n" % name)
            f.write("start: [%g, %g, 0]\ngoal: [%g, %g, 0]\nduration: %g\nuser_speed: 0.5\nseed: %d\nend: true\n"
                    % (START[0], START[1], GOAL[0], GOAL[1], a.duration, a.seed * 1000 + i))
        rows.append((name, difficulty, len(posts), 2 * c))
    with open(os.path.join(a.out, "manifest.csv"), "w") as f:
        f.write("world,difficulty,posts,narrowest_gap_m\n")
        for r in rows:
            f.write("%s,%.3f,%d,%.2f\n" % r)
    print("wrote %d worlds to %s" % (a.n, a.out))


if __name__ == "__main__":
    main()
