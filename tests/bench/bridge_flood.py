#!/usr/bin/env python3
"""A fake robot that floods `carenav navigate --bridge` with huge scan lines
and measures how long carenav's control loop goes without a command.

  python3 tests/bench/bridge_flood.py build/apps/carenav/carenav [BEAMS] [CYCLES]

It listens on a free port of 127.0.0.1, starts carenav (interbot profile,
user-intent-dwa, 10 Hz) against it, and each cycle sends a scan of BEAMS
ranges (default 100000: about 400 kB a line), odometry and the user's push,
without waiting; it records when each `cmd` arrives. Prints the largest and
the 99th-percentile gap between consecutive commands (the period is 100 ms)
and how many commands came per scan sent. Loopback only, bounded in count
and time.
"""
import math, os, socket, subprocess, sys, time

binary = sys.argv[1]
beams = int(sys.argv[2]) if len(sys.argv) > 2 else 100000
cycles = int(sys.argv[3]) if len(sys.argv) > 3 else 50
src = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

lst = socket.socket()
lst.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
lst.bind(("127.0.0.1", 0))
lst.listen(1)
port = lst.getsockname()[1]
proc = subprocess.Popen([binary, "-q", "navigate", "--bridge", f"127.0.0.1:{port}", "--profile",
                         os.path.join(src, "ini/interbot.ini"), "--plugin", "user-intent-dwa"],
                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
lst.settimeout(30)
conn, _ = lst.accept()
conn.setblocking(False)

def scan_line(t):
    rs = []
    for i in range(beams):
        a = -135 * math.pi / 180 + i * (270 * math.pi / 180) / (beams - 1)
        c = math.cos(a)
        d = 3.0 / c if c > 1e-3 else 0.0
        rs.append(f"{d:.3f}" if 0 < d < 30 else "0")
    return f"scan {t:.2f} laser {beams} " + " ".join(rs) + "\n"

line = scan_line(0.0).encode()  # the same shape each cycle
cmd_times, buf = [], b""
t0 = time.monotonic()
for k in range(cycles):
    t = 0.1 * k
    out = line + f"odom {t:.2f} 0 0 0 0 0\nintent {t:.2f} 0.2 0\n".encode()
    sent = 0
    while sent < len(out):
        try:
            sent += conn.send(out[sent:])
        except BlockingIOError:
            pass
        try:
            buf += conn.recv(65536)
        except BlockingIOError:
            pass
        lines = buf.split(b"\n")
        buf = lines.pop()
        cmd_times += [time.monotonic() for l in lines if l.startswith(b"cmd")]
    end = time.monotonic() + 0.1
    while time.monotonic() < end:
        try:
            buf += conn.recv(65536)
        except BlockingIOError:
            time.sleep(0.002)
        lines = buf.split(b"\n")
        buf = lines.pop()
        cmd_times += [time.monotonic() for l in lines if l.startswith(b"cmd")]
conn.setblocking(True)
conn.sendall(b"bye\n")
conn.settimeout(10)
try:
    while conn.recv(65536):
        pass
except OSError:
    pass
proc.wait(timeout=60)
gaps = sorted(b - a for a, b in zip(cmd_times, cmd_times[1:]))
p99 = gaps[min(len(gaps) - 1, int(0.99 * len(gaps)))] if gaps else float("nan")
print(f"beams {beams}, scans sent {cycles} in {time.monotonic() - t0:.1f} s, commands {len(cmd_times)}, "
      f"gap between commands: max {1000 * gaps[-1]:.0f} ms, p99 {1000 * p99:.0f} ms, "
      f"median {1000 * gaps[len(gaps) // 2]:.0f} ms; carenav exit {proc.returncode}")
