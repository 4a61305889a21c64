#!/usr/bin/env python3
"""Writes the hazard scenes of the perception recall report (issue 6 item 8,
docs/perceive.md): one open 5 m x 5 m floor plan (0.02 m per pixel, no walls,
so that the only thing in view is the hazard) and one carenav world file
(docs/simulate.md) per hazard in maps/worlds/hazards/.
The robot stands at (0.5, 2.5) facing +x; every hazard starts 1.3-1.5 m ahead
of it, inside the Kinect One's view (ini/isr-aiwalker.ini: 0.9 m high, 30 deg
down, the floor is seen from about 0.7 m ahead).
Run from anywhere: python3 scripts/make_hazard_worlds.py"""
import math
import os

RES = 0.02
SIZE = 5.0
OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "maps", "worlds", "hazards")

RAMP_DEG = 6.0
RAMP_LEN = 1.5
RAMP_RISE = round(RAMP_LEN * math.tan(math.radians(RAMP_DEG)), 4)

# name: (comment, features YAML)
SCENES = {
    "flat": ("Flat floor only: every cell in view is traversable.", ""),
    "stairs_down": (
        "Stairs going down away from the robot: 6 steps of 17 cm, treads 34 cm,\n"
        "1.2 m wide, a stairwell cut into the floor.",
        "  - type: stairs\n    rect: [1.8, 1.9, 3.84, 3.1]\n    direction: 0\n"
        "    steps: 6\n    rise: -0.17\n"),
    "stairs_up": (
        "Stairs going up away from the robot: 6 steps of 17 cm, treads 34 cm, 1.2 m wide.",
        "  - type: stairs\n    rect: [1.8, 1.9, 3.84, 3.1]\n    direction: 0\n"
        "    steps: 6\n    rise: 0.17\n"),
    "outlet": (
        "A floor outlet: a 10 x 10 cm opening 4 cm deep, 1.5 m ahead.",
        "  - type: hole\n    rect: [2.0, 2.45, 2.1, 2.55]\n    depth: 0.04\n"),
    "box2cm": (
        "A 2 cm high box (HOBBIT's 20 mm limit), 20 x 30 cm, 1.5 m ahead.",
        "  - type: step\n    rect: [2.0, 2.35, 2.2, 2.65]\n    height: 0.02\n"),
    "cable": (
        "A cable lying across the path: 2 cm wide, 1.5 cm high, 2 m long, 2 m ahead.",
        "  - type: step\n    rect: [2.5, 1.5, 2.52, 3.5]\n    height: 0.015\n"),
    "ramp6": (
        "A %g deg ramp (traversable, NOT an obstacle) across the whole floor:\n"
        "%g m long rising %g m, then a landing at that height." % (RAMP_DEG, RAMP_LEN, RAMP_RISE),
        "  - type: ramp\n    rect: [1.8, 0, %g, 5]\n    direction: 0\n    rise: %g\n"
        "  - type: step\n    rect: [%g, 0, 5, 5]\n    height: %g\n"
        % (1.8 + RAMP_LEN, RAMP_RISE, 1.8 + RAMP_LEN, RAMP_RISE)),
    "gutter": (
        "A gutter across the path: 15 cm wide, 10 cm deep, 4 m long, 1.5 m ahead.",
        "  - type: gutter\n    rect: [2.0, 0.5, 2.15, 4.5]\n    depth: 0.10\n"),
    "table": (
        "A table overhanging the path: top 0.75 m high, 4 cm thick, 1.2 x 0.9 m,\n"
        "5 cm legs in its corners.",
        "  - type: table\n    rect: [2.0, 2.0, 3.2, 2.9]\n    height: 0.75\n"
        "    thickness: 0.04\n    leg: 0.05\n"),
}


def main():
    os.makedirs(OUT, exist_ok=True)
    n = round(SIZE / RES)
    with open(os.path.join(OUT, "floor.pgm"), "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (n, n))
        f.write(bytes([254]) * (n * n))
    for name, (comment, features) in SCENES.items():
        with open(os.path.join(OUT, name + ".yaml"), "w") as f:
            f.write("# carenav hazard scene (docs/perceive.md), written by "
                    "scripts/make_hazard_worlds.py.\n")
            for line in comment.splitlines():
                f.write("# " + line + "\n")
            f.write("# Robot at (0.5, 2.5) facing +x.\n")
            f.write("format: 1\nname: %s\nmap: floor.pgm\nresolution: %g\norigin: [0, 0]\n"
                    % (name, RES))
            if features:
                f.write("features:\n" + features)


if __name__ == "__main__":
    main()
