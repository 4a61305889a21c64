#!/usr/bin/env python3
"""Table of a clutter benchmark run (results.jsonl of run_clutter.py), one row
per configuration, as Markdown:

  python3 tests/bench/clutter/table_clutter.py OUT/results.jsonl [--tolerance 0.3]

Columns: runs; success as carenav reported it; honest success (no
collision and the robot's true centre within --tolerance of the goal at the
end); runs with a collision; runs that timed out; other failures; mean and
max time of the honest successes (s); runs where the report and the truth
disagree. Standard library only.
"""
import argparse
import collections
import json


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("--tolerance", type=float, default=0.3,
                    help="m, goal tolerance of the honest check (the benchmark profile's 0.3)")
    a = ap.parse_args()
    by = collections.OrderedDict()
    for line in open(a.results):
        r = json.loads(line)
        by.setdefault(r["config"], []).append(r)
    print("| configuration | runs | success (reported) | success (honest) | collisions | timeouts "
          "| other failures | mean time s | max time s | report != truth |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for c, rs in by.items():
        n = len(rs)
        rep = sum(1 for r in rs if r.get("success"))
        honest = [r for r in rs if r.get("collisions", 0) == 0 and "goal reached" in r.get("outcome", "")
                  and r.get("final_goal_error_m", 1e9) <= a.tolerance]
        coll = sum(1 for r in rs if r.get("collisions", 0) > 0)
        tout = sum(1 for r in rs if r.get("collisions", 0) == 0 and "not reached" in r.get("outcome", ""))
        other = n - len(honest) - coll - tout
        times = [r["duration_s"] for r in honest]
        mism = sum(1 for r in rs if bool(r.get("success")) != (r in honest))
        print("| %s | %d | %.2f | %.2f | %d | %d | %d | %s | %s | %d |" % (
            c, n, rep / n, len(honest) / n, coll, tout, other,
            "%.1f" % (sum(times) / len(times)) if times else "-",
            "%.1f" % max(times) if times else "-", mism))
    fails = collections.Counter()
    for c, rs in by.items():
        for r in rs:
            if not r.get("success"):
                fails[(c, r.get("outcome", "?")[:60])] += 1
    if fails:
        print("\nFailures by outcome:\n")
        print("| configuration | outcome | runs |")
        print("|---|---|---|")
        for (c, o), k in sorted(fails.items()):
            print("| %s | %s | %d |" % (c, o, k))


if __name__ == "__main__":
    main()
