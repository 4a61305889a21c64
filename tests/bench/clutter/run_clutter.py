#!/usr/bin/env python3
"""Runs `carenav navigate` on every scenario of a clutter benchmark folder
(written by make_clutter.py) for each configuration (plugin x speed limits)
and appends one JSON line per run to OUT/results.jsonl (the run's summary
plus `config`, `v_max`, `w_max`). Each run's picture, navlog.csv and
summary.json go to OUT/<config>/<scenario>-<plugin>/.

  python3 tests/bench/clutter/run_clutter.py --bench /tmp/clutter1 \\
      --carenav build/apps/carenav/carenav --out /tmp/clutter1-results --jobs 2
  python3 tests/bench/clutter/table_clutter.py /tmp/clutter1-results/results.jsonl

Configurations (--configs, comma-separated; default all):
  goal-dwa@0.5   goal-dwa at 0.5 m/s, 1.57 rad/s
  goal-dwa@full  goal-dwa at the robot's 2.0 m/s, 4.0 rad/s
  mrpt-ptg@0.5, mrpt-ptg@full
  user-intent-dwa@0.5, user-intent-dwa@full  (a scripted user who walks the
                 A* route at the speed limit: the scenario's user_speed)
Runs already in results.jsonl are skipped (a benchmark can be resumed).
Standard library only.
"""
import argparse
import concurrent.futures
import json
import os
import re
import subprocess
import sys

SPEEDS = {"0.5": (0.5, 1.57), "full": (2.0, 4.0)}
ALL = ["goal-dwa@0.5", "goal-dwa@full", "mrpt-ptg@0.5", "mrpt-ptg@full",
       "user-intent-dwa@0.5", "user-intent-dwa@full"]


def run_one(carenav, scen, config, out, extra_sets):
    plugin, speed = config.split("@")
    v, w = SPEEDS[speed]
    cfg_dir = os.path.join(out, config.replace("@", "_"))
    os.makedirs(cfg_dir, exist_ok=True)
    path = scen
    if plugin == "user-intent-dwa":
        # the scripted user walks at the speed limit: a copy of the scenario
        # with user_speed set and its paths made absolute
        text = open(scen).read()
        base = os.path.dirname(os.path.abspath(scen))
        text = re.sub(r"^(world|profile): (.*)$",
                      lambda m: "%s: %s" % (m.group(1), os.path.normpath(os.path.join(base, m.group(2)))),
                      text, flags=re.M)
        text = re.sub(r"^user_speed: .*$", "user_speed: %g" % v, text, flags=re.M)
        path = os.path.join(cfg_dir, os.path.basename(scen))
        with open(path, "w") as f:
            f.write(text)
    cmd = [carenav, "-q", "navigate", "--scenario", path, "--plugin", plugin, "--json",
           "--out", cfg_dir, "--set", "robot.v_max=%g" % v, "--set", "robot.w_max=%g" % w]
    for s in extra_sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True)
    name = os.path.splitext(os.path.basename(scen))[0]
    try:
        runs = json.loads(p.stdout)
        r = runs[0]
    except (ValueError, IndexError):
        r = {"scenario": name, "plugin": plugin, "success": False, "collisions": 0,
             "outcome": "carenav exit %d: %s" % (p.returncode, p.stderr.strip()[-300:])}
    r.update({"config": config, "v_max": v, "w_max": w, "scenario": name})
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", required=True, help="folder written by make_clutter.py")
    ap.add_argument("--carenav", default="build/apps/carenav/carenav")
    ap.add_argument("--out", required=True)
    ap.add_argument("--configs", default=",".join(ALL))
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--limit", type=int, default=0, help="only the first N scenarios (0: all)")
    ap.add_argument("--every", type=int, default=1,
                    help="only every K-th scenario (graded worlds: K > 1 keeps the range of difficulty)")
    ap.add_argument("--set", action="append", default=[], help="extra profile override (repeatable)")
    a = ap.parse_args()
    configs = [c for c in a.configs.split(",") if c]
    for c in configs:
        if c not in ALL:
            ap.error("unknown configuration %s (known: %s)" % (c, ", ".join(ALL)))
    sdir = os.path.join(a.bench, "scenarios")
    scens = sorted(os.path.join(sdir, f) for f in os.listdir(sdir) if f.endswith(".yaml"))
    scens = scens[:: max(1, a.every)]
    if a.limit:
        scens = scens[: a.limit]
    os.makedirs(a.out, exist_ok=True)
    res = os.path.join(a.out, "results.jsonl")
    done = set()
    if os.path.exists(res):
        for line in open(res):
            r = json.loads(line)
            done.add((r["config"], r["scenario"]))
    todo = [(s, c) for c in configs for s in scens
            if (c, os.path.splitext(os.path.basename(s))[0]) not in done]
    with open(res, "a") as f, concurrent.futures.ThreadPoolExecutor(max(1, a.jobs)) as ex:
        futs = [ex.submit(run_one, a.carenav, s, c, a.out, a.set) for s, c in todo]
        for i, fu in enumerate(concurrent.futures.as_completed(futs)):
            r = fu.result()
            f.write(json.dumps(r) + "\n")
            f.flush()
            print("[%d/%d] %s %s: %s (%s)" % (i + 1, len(todo), r["config"], r["scenario"],
                                             "success" if r.get("success") else "FAIL", r.get("outcome")),
                  file=sys.stderr)


if __name__ == "__main__":
    main()
