#!/usr/bin/env python3
"""Writes the worlds of the navigation scenario suite (maps/scenarios/):
small PGM floor plans (0.05 m per pixel, white free, black wall) and their
carenav world files (docs/simulate.md) in maps/worlds/nav/.
Run from the repository root: python3 scripts/make_nav_worlds.py"""
import os

RES = 0.05
OUT = os.path.join(os.path.dirname(__file__), "..", "maps", "worlds", "nav")


class Plan:
    def __init__(self, w, h):
        self.nx, self.ny = round(w / RES), round(h / RES)
        self.px = [[254] * self.nx for _ in range(self.ny)]  # row 0 = top (y max)

    def wall(self, x0, y0, x1, y1):
        """Fills the rectangle [x0, x1] x [y0, y1] (metres) with wall."""
        for iy in range(self.ny):
            y = (self.ny - 1 - iy + 0.5) * RES
            if not (y0 <= y <= y1):
                continue
            for ix in range(self.nx):
                x = (ix + 0.5) * RES
                if x0 <= x <= x1:
                    self.px[iy][ix] = 0

    def border(self, t=0.1):
        w, h = self.nx * RES, self.ny * RES
        self.wall(0, 0, w, t)
        self.wall(0, h - t, w, h)
        self.wall(0, 0, t, h)
        self.wall(w - t, 0, w, h)

    def save(self, name):
        with open(os.path.join(OUT, name + ".pgm"), "wb") as f:
            f.write(b"P5\n%d %d\n255\n" % (self.nx, self.ny))
            for row in self.px:
                f.write(bytes(row))


def world(name, comment, features="", people="", plan=None):
    with open(os.path.join(OUT, name + ".yaml"), "w") as f:
        f.write("# carenav world (docs/simulate.md), written by scripts/make_nav_worlds.py.\n")
        for line in comment.strip().splitlines():
            f.write("# " + line + "\n")
        f.write("format: 1\nname: %s\nmap: %s.pgm\nresolution: %g\norigin: [0, 0]\n" % (name, plan or name, RES))
        if features:
            f.write("features:\n" + features)
        if people:
            f.write("people:\n" + people)


def box(x0, y0, x1, y1, h=0.8, note=""):
    return ("  - type: step%s\n    rect: [%g, %g, %g, %g]\n    height: %g\n"
            % ("   # " + note if note else "", x0, y0, x1, y1, h))


os.makedirs(OUT, exist_ok=True)

# A 14 m x 3 m corridor; boxes (not on the map: seen only by the sensors).
p = Plan(14, 3)
p.border()
p.save("corridor")
world("corridor", "14 m x 3 m corridor, walls only.")
world("corridor_boxes", "The corridor with boxes the map does not show: left, right, then one over the left edge of the way.",
      box(3.5, 2.2, 4.3, 2.9, note="left") + box(6.5, 0.1, 7.3, 0.8, note="right")
      + box(9.6, 1.65, 10.2, 2.2, note="over the left edge of the way"), plan="corridor")
# The person walks along the far wall to x = 7 m (10 s), crosses the corridor
# four times (t = 10-27 s, while the robots arrive) and stays at the wall. A
# person crossing back and forth for ever leaves gaps of about 2 s, too short
# for a 0.25 m/s robot to pass a 1 m crossing zone untouched.
world("corridor_person_crossing",
      "The corridor with a person crossing it at x = 7 m four times, then standing at the wall.",
      people="  - radius: 0.25\n    height: 1.7\n    speed: 0.5\n    loop: false\n"
             "    path: [[12.0, 2.55], [7.0, 2.55], [7.0, 0.45], [7.0, 2.55], [7.0, 0.45],"
             " [7.0, 2.55]]\n", plan="corridor")
world("corridor_person_towards", "The corridor with a person walking towards the start along y = 1.2 m.",
      people="  - radius: 0.25\n    height: 1.7\n    speed: 0.5\n    loop: false\n"
             "    path: [[13.0, 1.2], [1.0, 1.2]]\n", plan="corridor")

# The corridor closed by a door (wall) at x = 8 m.
p = Plan(14, 3)
p.border()
p.wall(8.0, 0, 8.1, 3)
p.save("corridor_closed")
world("corridor_closed", "The corridor closed by a door at x = 8 m.")

# Two 6 m x 6 m rooms joined by a door (0.8 m or 0.9 m wide) at y = 3 m.
for name, door in (("rooms_door80", 0.8), ("rooms_door90", 0.9)):
    p = Plan(12.1, 6)
    p.border()
    p.wall(6.0, 0, 6.1, 3 - door / 2)
    p.wall(6.0, 3 + door / 2, 6.1, 6)
    p.save(name)
    world(name, "Two 6 m x 6 m rooms joined by a %.0f cm door at x = 6 m, y = 3 m." % (door * 100))

# A room with a U-shaped trap opening towards the start (west).
p = Plan(12, 10)
p.border()
p.wall(6.0, 3.0, 6.1, 7.0)   # bottom of the U (east side)
p.wall(4.0, 3.0, 6.1, 3.1)   # lower arm
p.wall(4.0, 6.9, 6.1, 7.0)   # upper arm
p.save("u_trap")
world("u_trap", "A 12 m x 10 m room with a U-shaped trap (x 4-6 m, y 3-7 m) opening west.")

# A cluttered 10 m x 8 m room: furniture the map shows, posts it does not.
p = Plan(10, 8)
p.border()
for (x0, y0, x1, y1) in ((2.0, 1.5, 3.0, 2.5), (2.5, 5.0, 4.0, 6.0), (5.0, 3.0, 6.0, 4.2),
                         (7.0, 0.1, 7.6, 2.0), (7.0, 5.5, 8.5, 6.2)):
    p.wall(x0, y0, x1, y1)
p.save("cluttered")
world("cluttered", "A 10 m x 8 m room with furniture on the map and posts that are not.",
      box(4.2, 1.2, 4.5, 1.5, 1.0, "post") + box(6.6, 4.6, 6.9, 4.9, 1.0, "post")
      + box(3.5, 3.6, 3.8, 3.9, 1.0, "post"))

# A landing with a staircase going down (the walker must not be pushed onto it).
p = Plan(10, 4)
p.border()
p.save("stairs_down")
world("stairs_down", "A 10 m x 4 m landing; from x = 6 m a staircase goes down (6 steps of 0.17 m).",
      "  - type: stairs\n    rect: [6.0, 0.1, 9.9, 3.9]\n    direction: 0\n    steps: 6\n    rise: -0.17\n")
print("wrote", sorted(os.listdir(OUT)))
