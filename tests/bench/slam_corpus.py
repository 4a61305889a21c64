#!/usr/bin/env python3
"""SLAM and localisation over a corpus of real CARMEN logs, in one run.

For every log (default: every *-corrected.log.gz in tests/data/carmen) and
every input (laser only, and seeded noisy odometry, `carenav import carmen
--odometry-noise S`), it maps with `carenav slam`, evaluates against the
log's reference poses (`carenav eval`: ATE after SE(2) alignment, RPE per
2 m), and with --mrpt runs MRPT's icp-slam on the same rawlog with its demo
settings for a time and accuracy baseline. Then (--localize) it localises
each log's rawlog of another odometry seed on the map made from the first,
from a global start and from the known start, as `carenav localize` and
(--mrpt-loc) MRPT's pf-localization.

Prints one markdown table per part and writes OUT/results.jsonl, OUT/maps/
(each run's map.png beside the publishers' picture) and OUT/index.md.
Times are CPU seconds (user + system) of the process, so they mean the same
on a loaded machine; ratios are carenav / MRPT on the same input.

  tests/bench/slam_corpus.py --carenav build/apps/carenav/carenav --out /tmp/corpus \
      [--logs intel,csail] [--inputs laser,odo1,odo2,odo3] [--jobs 2] [--mrpt] \
      [--localize [--mrpt-loc]] [--reuse] [--set section.key=value ...] [--decimate N]
      [--reference-noise]
"""
import argparse
import concurrent.futures as cf
import json
import math
import os
import re
import shutil
import subprocess
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MRPT_CFG = "/usr/share/mrpt/config_files"


def run(cmd, log_path=None, cwd=None, limit=None):
    """Runs cmd; returns (exit code, CPU seconds of the child, wall seconds).
    With `limit` (CPU seconds) the child is stopped there (exit -9)."""
    out = open(log_path, "w") if log_path else subprocess.DEVNULL
    t0 = time.time()

    def cap():
        if limit:
            import resource
            resource.setrlimit(resource.RLIMIT_CPU, (int(limit), int(limit) + 1))

    p = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, cwd=cwd, preexec_fn=cap)
    _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    if log_path:
        out.close()
    return p.returncode, ru.ru_utime + ru.ru_stime, time.time() - t0


def tum_rows(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                rows.append([float(v) for v in line.split()])
    return rows


def eval_json(binary, est, ref, out_dir=None):
    """carenav eval, by index when both have one pose per scan (some logs
    repeat time stamps), else by time."""
    by_index = len(tum_rows(est)) == len(tum_rows(ref))
    cmd = [binary, "-q", "eval", "--est", est, "--ref", ref, "--rpe-dist", "2", "--json"]
    if by_index:
        cmd.append("--by-index")
    if out_dir:
        cmd += ["--out", out_dir]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return None
    return json.loads(p.stdout)


def metric(ev, *keys):
    v = ev
    for k in keys:
        if not isinstance(v, dict) or k not in v:
            return None
        v = v[k]
    return v


def rpe2(ev, stat="rmse"):
    for v in ev.get("rpe") or []:
        if abs(v.get("delta_m", -1) - 2) < 1e-9:
            return v["translation_m"][stat]
    return None


# ------------------------------------------------------------------ inputs

def import_log(a, log, inp, work):
    """The rawlog of one input of one log; returns (rawlog, reference tum)."""
    rawlog = os.path.join(work, "rawlog", f"{log}-{inp}.rawlog")
    tum = rawlog[: -len(".rawlog")] + ".tum"
    if os.path.exists(rawlog) and os.path.exists(tum):
        return rawlog, tum
    src = os.path.join(a.data, f"{log}-corrected.log.gz")
    if a.decimate > 1:
        src = decimated(src, a.decimate, os.path.join(work, "rawlog", f"{log}-every{a.decimate}.log.gz"))
    cmd = [a.carenav, "-q", "import", "carmen", src, "--out", rawlog]
    if inp == "laser":
        cmd += ["--odometry", "none"]
    else:
        cmd += ["--odometry-noise", inp[len("odo"):]]
    rc, _, _ = run(cmd, rawlog + ".log")
    if rc != 0:
        raise RuntimeError(f"import failed ({rc}): {' '.join(cmd)}")
    return rawlog, tum


LASER_MESSAGES = ("FLASER", "RLASER", "ROBOTLASER", "RAWLASER")


def decimated(src, n, dest):
    """A copy of the CARMEN log `src` with only every n-th laser message (all
    other lines kept): the same run recorded at 1/n of the scan rate, with
    n times the motion between scans."""
    import gzip
    if os.path.exists(dest):
        return dest
    k = 0
    # Two inputs of one log may get here at once (--jobs): each writes its own
    # part, and the same content replaces the same name.
    part = f"{dest}.{os.getpid()}.{threading.get_ident()}.part"
    with gzip.open(src, "rt", errors="replace") as f, gzip.open(part, "wt") as g:
        for line in f:
            if line.startswith(LASER_MESSAGES):
                k += 1
                if (k - 1) % n:
                    continue
            g.write(line)
    os.replace(part, dest)
    return dest


def headless_ini(template, rawlog, out_dir, dest, extra=None):
    """An MRPT app INI with the rawlog, output folder and no windows."""
    subs = {
        "rawlog_file": rawlog,
        "logOutput_dir": out_dir,
        "SHOW_PROGRESS_3D_REAL_TIME": "0",
        "SHOW_PROGRESS_IN_WINDOW": "0",
        "SAVE_3D_SCENE": "0",
        "SAVE_MAP_IMAGES": "0",
        "SAVE_POSE_LOG": "0",
        "LOG_FREQUENCY": "100000",
        "SHOW_PROGRESS_3D_REAL_TIME_DELAY_MS": "0",
    }
    subs.update(extra or {})
    lines = []
    with open(template) as f:
        for line in f:
            m = re.match(r"^\s*([A-Za-z_0-9]+)\s*=", line)
            if m and m.group(1) in subs:
                line = f"{m.group(1)}={subs[m.group(1)]}\n"
            elif re.match(r"^\s*verbosity_level", line):
                line = "verbosity_level = ERROR\n"
            lines.append(line)
    with open(dest, "w") as f:
        f.writelines(lines)


# ------------------------------------------------------------------ SLAM

def slam_job(a, log, inp, work):
    rawlog, ref = import_log(a, log, inp, work)
    name = f"{log}-{inp}"
    out = os.path.join(work, "slam", name)
    cmd = [a.carenav, "-q", "slam", "--profile", a.profile, "--rawlog", rawlog, "--out", out,
           "--method", a.method]
    for s in a.set:
        cmd += ["--set", s]
    prev = []
    if a.reuse and os.path.exists(os.path.join(out, "summary.json")):
        old = [json.loads(l) for l in open(os.path.join(work, "results.jsonl"))]
        prev = [r for r in old if r["part"] == "slam" and r["log"] == log and r["input"] == inp]
        rc, cpu, wall = 0, prev[0]["cpu_s"], prev[0]["wall_s"]
    else:
        shutil.rmtree(out, ignore_errors=True)
        rc, cpu, wall = run(cmd, out + ".log")
    r = {"part": "slam", "log": log, "input": inp, "method": a.method, "exit": rc,
         "cpu_s": round(cpu, 2), "wall_s": round(wall, 2)}
    est = os.path.join(out, "trajectory.tum")
    if rc == 0 and os.path.exists(est):
        ev = eval_json(a.carenav, est, ref, os.path.join(out, "eval"))
        if ev:
            r["ate_m"] = metric(ev, "ate", "translation_m", "rmse")
            r["ate_max_m"] = metric(ev, "ate", "translation_m", "max")
            r["rpe2_m"] = rpe2(ev)
            r["rpe2_mean_m"] = rpe2(ev, "mean")
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
        r["scans"] = s.get("steps")
        r["closures"] = s.get("loop_closures")
        r["rejected"] = s.get("loop_rejected")
        shutil.copy(os.path.join(out, "map.png"), os.path.join(work, "maps", f"{name}.png"))
    if a.mrpt and not a.reuse:
        r.update(mrpt_slam(a, rawlog, ref, os.path.join(work, "mrpt", name), est))
    elif a.reuse and prev:
        r.update({k: v for k, v in prev[0].items() if k in ("mrpt_exit", "mrpt_cpu_s")})
        if prev[0].get("mrpt_exit") == 0:
            r.update(mrpt_eval(a, ref, os.path.join(work, "mrpt", name)))
    return r


def mrpt_slam(a, rawlog, ref, out, carenav_tum):
    """MRPT's icp-slam, demo settings, on the same rawlog."""
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    ini = os.path.join(out, "icp.ini")
    headless_ini(os.path.join(MRPT_CFG, "icp-slam", "icp-slam_demo_classic.ini"), rawlog, out, ini)
    rc, cpu, _ = run(["icp-slam", ini], os.path.join(out, "run.log"), cwd=out, limit=a.mrpt_limit)
    r = {"mrpt_exit": rc, "mrpt_cpu_s": round(cpu, 2)}
    if rc == 0:
        r.update(mrpt_eval(a, ref, out))
    return r


def mrpt_eval(a, ref, out):
    """ATE and RPE of icp-slam's log_estimated_path.txt ("step x y phi", one
    step per rawlog entry: with odometry the entries alternate odometry,
    scan, so the pose after each scan is every second step)."""
    path = os.path.join(out, "log_estimated_path.txt")
    if not os.path.exists(path):
        return {}
    refs = tum_rows(ref)
    rows = [l.split() for l in open(path) if l.strip() and not l.startswith("%")]
    per_scan = len(rows) // len(refs) if refs and len(rows) % len(refs) == 0 else 1
    tum = os.path.join(out, "trajectory.tum")
    with open(tum, "w") as f:
        for i in range(min(len(refs), len(rows) // per_scan)):
            row = rows[(i + 1) * per_scan - 1]
            x, y, phi = float(row[1]), float(row[2]), float(row[3])
            f.write(f"{refs[i][0]:.6f} {x} {y} 0 0 0 {math.sin(phi / 2)} {math.cos(phi / 2)}\n")
    ev = eval_json(a.carenav, tum, ref)
    if not ev:
        return {}
    return {"mrpt_ate_m": metric(ev, "ate", "translation_m", "rmse"), "mrpt_rpe2_m": rpe2(ev)}


# ------------------------------------------------------------------ localisation

def loc_job(a, log, map_input, loc_input, mode, work):
    """Localises the rawlog of `loc_input` on the map made from `map_input`.
    Reference: that slam run's trajectory (the map's frame), by index."""
    rawlog, _ = import_log(a, log, loc_input, work)
    slam_out = os.path.join(work, "slam", f"{log}-{map_input}")
    ref = os.path.join(slam_out, "trajectory.tum")
    r = {"part": "localize", "log": log, "map": map_input, "input": loc_input, "mode": mode}
    if not os.path.exists(ref):
        r["exit"] = None
        return r
    out = os.path.join(work, "loc", f"{log}-{mode}")
    shutil.rmtree(out, ignore_errors=True)
    cmd = [a.carenav, "-q", "localize", "--profile", a.profile, "--map",
           os.path.join(slam_out, "map.gridmap.gz"), "--rawlog", rawlog, "--out", out]
    if mode == "global":
        cmd.append("--global")
    else:
        x, y, _, _, _, qz, qw = tum_rows(ref)[0][1:8]
        cmd += ["--init", f"{x},{y},{math.degrees(2 * math.atan2(qz, qw))},0.3,0.3,5"]
    for s in a.set:
        if s.startswith("localization."):
            cmd += ["--set", s]
    rc, cpu, _ = run(cmd, out + ".log")
    r.update({"exit": rc, "cpu_s": round(cpu, 2)})
    if rc != 0:
        return r
    r.update(track_stats(os.path.join(out, "track.tum"), ref, os.path.join(out, "summary.json")))
    if a.mrpt_loc:
        r.update(mrpt_loc(a, rawlog, slam_out, ref, mode, os.path.join(work, "mrpt-loc",
                                                                      f"{log}-{mode}")))
    return r


def track_stats(track, ref, summary):
    with open(summary) as f:
        s = json.load(f)
    tr, rf = tum_rows(track), tum_rows(ref)
    n = min(len(tr), len(rf))
    err = [math.hypot(tr[i][1] - rf[i][1], tr[i][2] - rf[i][2]) for i in range(n)]
    conv = s.get("convergence_scans")
    r = {"scans": n, "losses": s.get("losses"), "injections": s.get("injections"),
         "converged_after": conv}
    if conv:
        after = err[max(0, conv - 1):]
        r["ate_after_m"] = math.sqrt(sum(e * e for e in after) / len(after)) if after else None
        r["within_03"] = sum(e <= 0.3 for e in after) / len(after) if after else None
    r["ate_all_m"] = math.sqrt(sum(e * e for e in err) / n) if n else None
    return r


def map_bounds(slam_out):
    """x0, y0, x1, y1 of the map that `carenav slam` wrote (map.yaml + .pgm)."""
    res = ox = oy = None
    with open(os.path.join(slam_out, "map.yaml")) as f:
        for line in f:
            k, _, v = line.partition(":")
            if k.strip() == "resolution":
                res = float(v)
            elif k.strip() == "origin":
                ox, oy = [float(t) for t in v.strip(" []\n").split(",")[:2]]
    with open(os.path.join(slam_out, "map.pgm"), "rb") as f:
        tok = []
        while len(tok) < 3:
            line = f.readline()
            if not line.startswith(b"#"):
                tok += line.split()
    w, h = int(tok[1]), int(tok[2])
    return ox, oy, ox + w * res, oy + h * res


def mrpt_loc(a, rawlog, slam_out, ref, mode, out):
    """MRPT's pf-localization (its observation-only demo settings) on the
    same map and rawlog: time only (it writes per-iteration files, not a
    track per scan)."""
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    ini = os.path.join(out, "pf.ini")
    extra = {"map_file": os.path.join(slam_out, "map.gridmap.gz"), "logOutput_dir": out,
             "experimentRepetitions": "1", "3DSceneFrequency": "1000000", "init_PDF_mode": "0"}
    if mode == "global":
        x0, y0, x1, y1 = map_bounds(slam_out)
    else:
        x, y = tum_rows(ref)[0][1:3]
        x0, y0, x1, y1 = x - 0.3, y - 0.3, x + 0.3, y + 0.3
        extra["particles_count"] = "2000"
    extra.update({"init_PDF_min_x": x0, "init_PDF_max_x": x1, "init_PDF_min_y": y0,
                  "init_PDF_max_y": y1})
    headless_ini(os.path.join(MRPT_CFG, "pf-localization", "localization_demo_obsonly_rawlog.ini"),
                 rawlog, out, ini, {k: str(v) for k, v in extra.items()})
    rc, cpu, _ = run(["pf-localization", ini], os.path.join(out, "run.log"), cwd=out,
                     limit=a.mrpt_limit)
    return {"mrpt_exit": rc, "mrpt_cpu_s": round(cpu, 2)}


# ------------------------------------------------------------------ tables

def fmt(v, d=3):
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.{d}f}"
    return str(v)


def slam_table(rows, split=False):
    out = ["| log | input | scans | ATE (m) | ATE max (m) | RPE 2 m rmse (m) | RPE 2 m mean (m) |"
           + (" s_ref 2 m (m) | s_est 2 m (m) |" if split else "") +
           " closures | CPU (s) | MRPT icp-slam ATE (m) | MRPT CPU (s) | CPU ratio |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|" + ("---|---|" if split else "")]
    for r in rows:
        ratio = (r["cpu_s"] / r["mrpt_cpu_s"]) if r.get("mrpt_cpu_s") else None
        ex = "" if r["exit"] == 0 else f" (exit {r['exit']})"
        mex = "" if r.get("mrpt_exit", 0) == 0 else f" (exit {r['mrpt_exit']})"
        out.append(f"| {r['log']} | {r['input']}{ex} | {fmt(r.get('scans'))} | {fmt(r.get('ate_m'))}"
                   f" | {fmt(r.get('ate_max_m'))} | {fmt(r.get('rpe2_m'))} | {fmt(r.get('rpe2_mean_m'))}"
                   + (f" | {fmt(r.get('s_ref_m'))} | {fmt(r.get('s_est_m'))}" if split else "") +
                   f" | {fmt(r.get('closures'))}"
                   f" | {fmt(r['cpu_s'], 1)} | {fmt(r.get('mrpt_ate_m'))}{mex}"
                   f" | {fmt(r.get('mrpt_cpu_s'), 1)} | {fmt(ratio, 2)} |")
    return "\n".join(out)


def loc_table(rows):
    out = ["| log | map | rawlog | start | converged after (scans) | ATE after (m) |"
           " within 0.3 m | losses | injections | CPU (s) | MRPT CPU (s) | CPU ratio |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ratio = (r["cpu_s"] / r["mrpt_cpu_s"]) if r.get("mrpt_cpu_s") else None
        mcpu = fmt(r.get("mrpt_cpu_s"), 1)
        if r.get("mrpt_exit") not in (0, None):
            mcpu = f"> {mcpu} (stopped)" if r.get("mrpt_exit") in (-9, -24) else f"exit {r['mrpt_exit']}"
            ratio = None
        w = r.get("within_03")
        out.append(f"| {r['log']} | {r['map']} | {r['input']} | {r['mode']} |"
                   f" {fmt(r.get('converged_after')) if r.get('converged_after') else 'never'} |"
                   f" {fmt(r.get('ate_after_m'))} | {fmt(100 * w, 1) + ' %' if w is not None else '-'}"
                   f" | {fmt(r.get('losses'))} | {fmt(r.get('injections'))} | {fmt(r.get('cpu_s'), 1)}"
                   f" | {mcpu} | {fmt(ratio, 2)} |")
    return "\n".join(out)


def reference_noise(a, logs, work, results):
    """--reference-noise: each slam row gets the reference's and its own
    error per 2 m (the three-cornered hat of tests/bench/slam_reference_noise.py,
    over the RPE pairs with a pairwise ICP)."""
    try:
        import slam_reference_noise as srn
    except ImportError as e:
        print(f"--reference-noise: {e} (it needs python3-numpy and python3-scipy)", file=sys.stderr)
        return
    for log in logs:
        rows = [r for r in results if r["log"] == log and r["exit"] == 0]
        if not rows:
            continue
        src = os.path.join(a.data, f"{log}-corrected.log.gz")
        if a.decimate > 1:
            src = os.path.join(work, "rawlog", f"{log}-every{a.decimate}.log.gz")
        ref = os.path.join(work, "rawlog", f"{log}-{rows[0]['input']}.tum")
        ests = [os.path.join(work, "slam", f"{log}-{r['input']}", "trajectory.tum") for r in rows]
        try:
            _, _, split = srn.split_errors(src, ref, ests)
        except ValueError as e:
            print(f"--reference-noise {log}: {e}", file=sys.stderr)
            continue
        for r, sp in zip(rows, split):
            r["s_ref_m"], r["s_est_m"] = sp["own"][0], sp["own"][1]


def write_index(work, logs, inputs, data):
    lines = ["# SLAM corpus maps", ""]
    for log in logs:
        pub = os.path.join(data, f"{log}-corrected.png")
        if os.path.exists(pub):
            shutil.copy(pub, os.path.join(work, "maps", f"{log}-publisher.png"))
        lines.append(f"## {log}")
        lines.append("")
        cells = [f"![{log} publisher](maps/{log}-publisher.png)"]
        cells += [f"![{log} {i}](maps/{log}-{i}.png)" for i in inputs]
        lines.append("| publisher | " + " | ".join(inputs) + " |")
        lines.append("|" + "---|" * (len(inputs) + 1))
        lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    with open(os.path.join(work, "index.md"), "w") as f:
        f.write("\n".join(lines))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--carenav", default=os.path.join(ROOT, "build/apps/carenav/carenav"))
    ap.add_argument("--out", required=True)
    ap.add_argument("--data", default=os.path.join(ROOT, "tests/data/carmen"))
    ap.add_argument("--profile", default=os.path.join(ROOT, "ini/defaults.ini"))
    ap.add_argument("--logs", default="", help="comma-separated (default: every log in --data)")
    ap.add_argument("--inputs", default="laser,odo1,odo2,odo3")
    ap.add_argument("--method", default="icp-graph")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--mrpt", action="store_true", help="MRPT's icp-slam on the same rawlogs too")
    ap.add_argument("--mrpt-loc", action="store_true",
                    help="MRPT's pf-localization on the same maps and rawlogs too (slow: "
                         "40000 particles from a global start)")
    ap.add_argument("--mrpt-limit", type=float, default=600,
                    help="CPU seconds after which an MRPT baseline run is stopped (shown as a "
                         "lower bound of its time)")
    ap.add_argument("--localize", action="store_true", help="localisation part too")
    ap.add_argument("--reuse", action="store_true",
                    help="re-evaluate and tabulate the slam runs already in --out (no mapping)")
    ap.add_argument("--set", action="append", default=[], help="profile override (repeatable)")
    ap.add_argument("--reference-noise", action="store_true",
                    help="split each run's RPE into the reference's own error per 2 m and the\n"
                         "run's (tests/bench/slam_reference_noise.py; needs numpy and scipy)")
    ap.add_argument("--decimate", type=int, default=1,
                    help="keep only every N-th scan of each log (the same run at 1/N of the "
                         "scan rate: a check that the front end holds at other rates)")
    a = ap.parse_args()
    a.carenav = os.path.abspath(a.carenav)
    if (a.mrpt or a.mrpt_loc) and not shutil.which("icp-slam"):
        sys.exit("--mrpt: icp-slam not found (Debian package mrpt-apps)")
    logs = [l for l in a.logs.split(",") if l] or sorted(
        f[: -len("-corrected.log.gz")] for f in os.listdir(a.data) if f.endswith("-corrected.log.gz"))
    inputs = [i for i in a.inputs.split(",") if i]
    for i in inputs:
        if i != "laser" and not re.fullmatch(r"odo\d+", i):
            sys.exit(f"unknown input {i} (laser or odoN, N the noise seed)")
    work = os.path.abspath(a.out)
    for d in ("rawlog", "slam", "maps", "mrpt", "loc", "mrpt-loc"):
        os.makedirs(os.path.join(work, d), exist_ok=True)

    results = []
    with cf.ThreadPoolExecutor(a.jobs) as ex:
        futs = [ex.submit(slam_job, a, l, i, work) for l in logs for i in inputs]
        for f in cf.as_completed(futs):
            r = f.result()
            print(f"slam {r['log']} {r['input']}: exit {r['exit']} ATE {fmt(r.get('ate_m'))}"
                  f" RPE2 {fmt(r.get('rpe2_m'))} cpu {r['cpu_s']}", file=sys.stderr, flush=True)
            results.append(r)
    order = {(l, i): n for n, (l, i) in enumerate((l, i) for l in logs for i in inputs)}
    results.sort(key=lambda r: order[(r["log"], r["input"])])
    if a.reference_noise:
        reference_noise(a, logs, work, results)
    loc = []
    if a.localize:
        odo = [i for i in inputs if i != "laser"]
        map_in, loc_in = (odo[0], odo[1] if len(odo) > 1 else odo[0]) if odo else ("laser", "laser")
        with cf.ThreadPoolExecutor(a.jobs) as ex:
            futs = [ex.submit(loc_job, a, l, map_in, loc_in, m, work)
                    for l in logs for m in ("global", "tracking")]
            for f in cf.as_completed(futs):
                r = f.result()
                print(f"localize {r['log']} {r['mode']}: exit {r['exit']} within"
                      f" {fmt(r.get('within_03'))}", file=sys.stderr, flush=True)
                loc.append(r)
        loc.sort(key=lambda r: (logs.index(r["log"]), r["mode"]))
    with open(os.path.join(work, "results.jsonl"), "w") as f:
        for r in results + loc:
            f.write(json.dumps(r) + "\n")
    write_index(work, logs, inputs, a.data)
    print(slam_table(results, a.reference_noise))
    if loc:
        print()
        print(loc_table(loc))


if __name__ == "__main__":
    main()
