#!/usr/bin/env python3
"""Corrupted-rawlog battery: makes N seeded corrupt copies of a rawlog and
reads each with `carenav rawlog info` under an address-space limit, then
tallies how the binary ended. The promise (docs/rawlog.md): exit 0 (what
could be read was read) or exit 2 naming the file, never a signal, never
exit 1, never more memory than the limit.

  python3 tests/bench/corrupt_rawlogs.py --carenav build/apps/carenav/carenav \\
      --rawlog "/usr/share/mrpt/datasets/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog" \\
      --n 450 --seed 1 --out /tmp/corrupt

Corruptions, in turn: a flipped byte, 8 random bytes overwritten, a 4-byte
little-endian field set to a huge value (0xffffffff, 0x7fffffff, 2^31, 2^24)
at a random offset, a cut at a random length, a random block duplicated.
Offsets are drawn from the first 64 KiB (where entry headers are dense) half
the time, else from the whole file. Gzip rawlogs are corrupted after
decompression (the reader sees the same bytes). Cases that misbehave are
kept in OUT/bad/ with the command to replay them. Standard library only.
"""
import argparse
import collections
import gzip
import os
import random
import shlex
import subprocess
import sys


def corrupt(data, rng, k):
    b = bytearray(data)
    off = rng.randrange(min(len(b), 65536)) if rng.random() < 0.5 else rng.randrange(len(b))
    kind = k % 5
    if kind == 0:
        b[off] ^= 1 << rng.randrange(8)
        return bytes(b), "flip@%d" % off
    if kind == 1:
        b[off:off + 8] = bytes(rng.randrange(256) for _ in range(8))
        return bytes(b), "bytes@%d" % off
    if kind == 2:
        v = rng.choice([0xFFFFFFFF, 0x7FFFFFFF, 0x80000000, 0x01000000])
        b[off:off + 4] = v.to_bytes(4, "little")
        return bytes(b), "size%#x@%d" % (v, off)
    if kind == 3:
        return bytes(b[:off]), "cut@%d" % off
    n = rng.randrange(1, 4096)
    return bytes(b[:off] + b[off:off + n] + b[off:]), "dup%d@%d" % (n, off)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--carenav", required=True)
    ap.add_argument("--rawlog", required=True, help="a valid rawlog (plain or gzip)")
    ap.add_argument("--n", type=int, default=450)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", required=True)
    ap.add_argument("--limit-kb", type=int, default=3000000, help="ulimit -v (3000000)")
    a = ap.parse_args()
    raw = open(a.rawlog, "rb").read()
    if raw[:2] == b"\x1f\x8b":
        raw = gzip.decompress(raw)
    os.makedirs(os.path.join(a.out, "bad"), exist_ok=True)
    rng = random.Random(a.seed)
    tally = collections.Counter()
    bad = 0
    path = os.path.join(a.out, "case.rawlog")
    for k in range(a.n):
        data, what = corrupt(raw, rng, k)
        with open(path, "wb") as f:
            f.write(data)
        cmd = "ulimit -v %d; exec %s -q rawlog info %s" % (a.limit_kb, shlex.quote(a.carenav),
                                                        shlex.quote(path))
        p = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, errors="replace")
        rc = p.returncode
        ok = rc == 0 or (rc == 2 and path in p.stderr)
        tally["exit %d" % rc if rc >= 0 else "signal %d" % -rc] += 1
        if not ok:
            bad += 1
            keep = os.path.join(a.out, "bad", "%04d-%s.rawlog" % (k, what.replace("@", "-")))
            os.replace(path, keep)
            print("BAD %s: exit %d: %s\n  replay: %s -q rawlog info %s" %
                  (what, rc, p.stderr.strip()[-300:], a.carenav, keep))
    print("%d corrupt copies of %s (seed %d): %s; misbehaved: %d" %
          (a.n, os.path.basename(a.rawlog), a.seed,
           ", ".join("%s %d" % kv for kv in sorted(tally.items())), bad))
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
