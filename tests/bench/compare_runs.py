#!/usr/bin/env python3
"""Compares two `carenav navigate --json` outputs run by run (scenario,
plugin): every field but the timings and memory samples must be equal.
Prints the runs that differ and exits 1 when any does.

  python3 tests/bench/compare_runs.py before.json after.json
"""
import json
import sys

TIMINGS = {'wall_seconds', 'cycle_ms_mean', 'cycle_ms_max', 'work_ms_p99', 'work_ms_max',
           'work_ms_p99_per_10min', 'rss_mb_per_minute', 'perception_ms_mean', 'outputs'}


def runs(path):
    with open(path) as f:
        return {(r.get('scenario'), r.get('plugin')): r for r in json.load(f)}


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    a, b = runs(sys.argv[1]), runs(sys.argv[2])
    differ = 0
    for key in sorted(set(a) | set(b), key=str):
        ra, rb = a.get(key), b.get(key)
        if ra is None or rb is None:
            print(key, 'only in', sys.argv[2] if ra is None else sys.argv[1])
            differ += 1
            continue
        d = [(f, ra.get(f), rb.get(f)) for f in sorted(set(ra) | set(rb))
             if f not in TIMINGS and ra.get(f) != rb.get(f)]
        if d:
            differ += 1
            print(key, d)
    print(f'{len(a)} runs before, {len(b)} after, {differ} differ')
    return 1 if differ else 0


if __name__ == '__main__':
    sys.exit(main())
