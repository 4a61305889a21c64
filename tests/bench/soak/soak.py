#!/usr/bin/env python3
"""Soak: long simulated runs of carenav navigation with people walking, to
show that memory stays flat, there are no collisions and the robot's work
per control period stays stable over an hour (docs/BENCHMARKS.md "Soak").

  python3 tests/bench/soak/soak.py --carenav build/apps/carenav/carenav \\
      --out /tmp/soak [--duration 3600] [--jobs 2]

Runs (each a patrol: goals visited in turn until --duration, simulated,
as fast as the computer can):
  goal-apartment     Interbot (localisation on the map from its lidar, depth
                     camera through the perception pipeline) patrolling the
                     apartment's living room around the table, while one
                     person walks back and forth across the room and another
                     a loop in the corridor (a copy of the apartment world
                     with the second person, OUT/apartment-people.yaml)
  walker-apartment   a scripted user walking the ISR-AIWALKER (depth camera
                     and range array) between the same places
  goal-clutter       the clutter benchmark's robot (tests/bench/clutter) at
                     0.5 m/s, 1.57 rad/s, back and forth through a generated
                     post field (make_clutter.py --seed 5, the easiest of 9:
                     the soak is about an hour of work, the clutter
                     benchmark about getting through) while one person
                     walks along the south wall through the field and
                     another crosses the room between the field and the goal
  goal-clutter-ptg   the same with the mrpt-ptg plugin
Each run writes OUT/<run>/<scenario>/{summary.json,navlog.csv,run.png}; the table
(Markdown) is printed and written to OUT/soak.md. Standard library only.
"""
import argparse
import concurrent.futures
import csv
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

PEOPLE = """people:
  - name: along-the-wall
    radius: 0.25
    height: 1.7
    speed: 0.5
    loop: true
    path: [[0.6, 0.7], [12.0, 0.7]]
  - name: crossing-east
    radius: 0.25
    height: 1.7
    speed: 0.4
    loop: true
    path: [[10.1, 4.4], [10.1, 0.6]]
"""


LIVING_ROOM_PERSON = """  - name: living-room
    radius: 0.25
    height: 1.7
    speed: 0.5
    loop: true
    path: [[0.8, 2.7], [4.3, 2.7]]
"""


def apartment_world(out):
    """A copy of the apartment world with a second person, in the living room."""
    src = os.path.join(HERE, "..", "..", "..", "maps", "worlds", "apartment.yaml")
    text = open(src).read()
    text = text.replace("map: apartment.png", "map: %s" % os.path.abspath(
        os.path.join(os.path.dirname(src), "apartment.png")))
    text = text.rstrip("\n") + "\n" + LIVING_ROOM_PERSON
    world = os.path.join(out, "apartment-people.yaml")
    with open(world, "w") as f:
        f.write(text)
    return world


def apartment_scenario(out, name, world):
    """The repository's scenario, pointed at the world with two people."""
    text = open(os.path.join(HERE, name + ".yaml")).read()
    text = text.replace("world: ../../../maps/worlds/apartment.yaml", "world: " + world)
    text = text.replace("profile: ../../../", "profile: %s/" % os.path.abspath(
        os.path.join(HERE, "..", "..", "..")))
    scen = os.path.join(out, name + ".yaml")
    with open(scen, "w") as f:
        f.write(text)
    return scen


def clutter_scenario(out, duration):
    """Generates the clutter world (with people) and its patrol scenario."""
    bench = os.path.join(out, "clutter")
    subprocess.run([sys.executable, os.path.join(HERE, "..", "clutter", "make_clutter.py"),
                    "--n", "9", "--seed", "5", "--out", bench], check=True,
                   stdout=subprocess.DEVNULL)
    with open(os.path.join(bench, "manifest.csv")) as f:
        rows = sorted(csv.DictReader(f), key=lambda r: float(r["difficulty"]))
    world = os.path.join(bench, "worlds", rows[0]["world"] + ".yaml")  # the easiest field
    text = open(world).read()
    if "people:" not in text:
        text = text.replace("\nend: true", "\n" + PEOPLE + "end: true") if "\nend: true" in text \
            else text.rstrip("\n") + "\n" + PEOPLE
        with open(world, "w") as f:
            f.write(text)
    scen = os.path.join(out, "goal-clutter.yaml")
    with open(scen, "w") as f:
        f.write("# Soak in a generated post field (tests/bench/soak/soak.py)\nformat: 1\n"
                "world: %s\nprofile: %s\nstart: [1.0, 2.5, 0]\n"
                "patrol:\n  - [11.0, 2.5, 0]\n  - [1.0, 2.5, 180]\n"
                "duration: %g\nend: true\n" % (world, os.path.join(bench, "robot.ini"), duration))
    return scen, ["robot.v_max=0.5", "robot.w_max=1.57"], []


def run(carenav, name, scen, sets, extra, out, duration):
    d = os.path.join(out, name)
    os.makedirs(d, exist_ok=True)
    # Collisions are counted, not the end of the run: the soak is about the
    # whole hour (a person walking into the robot is a collision too).
    cmd = [carenav, "-q", "navigate", "--scenario", scen, "--out", d, "--duration", str(duration),
           "--continue-after-collision"]
    for s in sets:
        cmd += ["--set", s]
    cmd += extra
    p = subprocess.run(cmd, capture_output=True, text=True)
    stem = os.path.splitext(os.path.basename(scen))[0]  # navigate writes OUT/<scenario>/
    try:
        with open(os.path.join(d, stem, "summary.json")) as f:
            s = json.load(f)
    except (OSError, ValueError):
        sys.exit("soak.py: %s failed (exit %d): %s" % (name, p.returncode, p.stderr.strip()))
    s["run"] = name
    return s


def fmt_row(s):
    rss = [v for v in s["rss_mb_per_minute"] if v is not None]
    warm = rss[min(5, len(rss) - 1)] if rss else float("nan")  # after 5 simulated minutes
    win = s["work_ms_p99_per_10min"]
    legs = s["legs_completed"] + s["legs_missed"] + s["legs_failed"]
    return "| %s | %.0f | %.0f | %d / %d / %d | %d | %.1f | %.1f | %.1f | %+.1f | %.2f | %s | %.2f | %.1f | %s |" % (
        s["run"], s["duration_s"], s["wall_seconds"], s["legs_completed"], s["legs_missed"], legs,
        s["collisions"], rss[0] if rss else float("nan"),
        warm, max(rss) if rss else float("nan"), (rss[-1] - warm) if rss else float("nan"),
        s["work_ms_p99"], " ".join("%.2f" % v for v in win), s["cycle_ms_mean"], s["work_ms_max"],
        s["outcome"])


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--carenav", required=True, help="the carenav binary")
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--duration", type=float, default=3600, help="simulated s per run (3600)")
    ap.add_argument("--jobs", type=int, default=2, help="runs at once (2)")
    ap.add_argument("--runs", default="goal-apartment,walker-apartment,goal-clutter,goal-clutter-ptg",
                    help="comma-separated subset of the runs")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    world = apartment_world(a.out)
    runs = {r: (apartment_scenario(a.out, r, world), [], []) for r in
            ("goal-apartment", "walker-apartment")}
    if "goal-clutter" in a.runs:
        runs["goal-clutter"] = clutter_scenario(a.out, a.duration)
        scen, sets, _ = runs["goal-clutter"]
        runs["goal-clutter-ptg"] = (scen, sets, ["--plugin", "mrpt-ptg"])
    chosen = [r for r in a.runs.split(",") if r]
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        futs = [ex.submit(run, os.path.abspath(a.carenav), r, *runs[r], a.out, a.duration)
                for r in chosen]
        results = [f.result() for f in futs]
    head = ("| run | simulated s | wall s | legs reached / missed / all | collisions | RSS start MiB | "
            "RSS at 5 min | RSS max | RSS end - 5 min | work p99 ms (CPU) | p99 per 10 min | "
            "navigator mean ms | work max ms | outcome |\n|" + "---|" * 14)
    table = "\n".join([head] + [fmt_row(s) for s in results])
    print(table)
    with open(os.path.join(a.out, "soak.md"), "w") as f:
        f.write(table + "\n")


if __name__ == "__main__":
    main()
