#!/usr/bin/env python3
"""Memory and CPU time of identification and validation on a long log (bench/README.md, "Offline").

Records a joystick run of the built-in simulator (default an hour at 80 Hz,
from rest, every effect on), then runs `plsa identify` with the demo's
options (input-side scheduling) and `plsa validate` of that model on the same
log, each as its own process, and reads each one's peak resident memory and
CPU time (user + system, every thread) from the kernel (wait4's rusage).
Prints them per sample and per hour of data; --json FILE writes them.

Usage: python3 bench/offline_cost.py [--build build] [--minutes 60] [--json FILE]
"""
import argparse
import json
import os
import subprocess
import tempfile
import time


def measured(cmd):
    """(peak resident KB, CPU seconds, wall seconds) of one process; its output discarded, its failure fatal."""
    start = time.monotonic()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise SystemExit(f"offline_cost: {' '.join(cmd)} exited with {proc.returncode}:\n{err}")
    return usage.ru_maxrss, usage.ru_utime + usage.ru_stime, time.monotonic() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                                     "build"))
    ap.add_argument("--minutes", type=float, default=60.0, help="length of the recorded run (default 60)")
    ap.add_argument("--json", metavar="FILE", help="write the figures here")
    a = ap.parse_args()
    exe = os.path.join(a.build, "apps", "plsa")
    if not os.access(exe, os.X_OK):
        raise SystemExit(f"offline_cost: no {exe}; build first (scripts/plsa-dev setup)")
    figures = {"minutes": a.minutes, "steps": {}}
    with tempfile.TemporaryDirectory() as tmp:
        log, model = os.path.join(tmp, "run.csv"), os.path.join(tmp, "model.json")
        subprocess.run([exe, "simulate", "--experiment", "joystick", "--duration", str(a.minutes * 60), "--seed", "6",
                        "--out", log], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(log) as f:
            samples = sum(1 for _ in f) - 1
        figures["samples"] = samples
        hours = samples / 80.0 / 3600.0
        steps = {"identify": [exe, "identify", "--log", log, "--scheduling", "input", "--out", model],
                 "validate": [exe, "validate", "--model", model, "--log", log]}
        for name, cmd in steps.items():
            kb, cpu, wall = measured(cmd)
            figures["steps"][name] = {"peak_kb": kb, "kb_per_sample": kb / samples, "cpu_s": cpu,
                                      "cpu_s_per_hour": cpu / hours, "wall_s": wall}
    print(f"{samples} samples ({a.minutes:g} min at 80 Hz)")
    for name, s in figures["steps"].items():
        print(f"{name}: peak {s['peak_kb'] / 1024:.0f} MB ({s['kb_per_sample']:.2f} KB per sample), "
              f"CPU {s['cpu_s']:.1f} s ({s['cpu_s_per_hour']:.0f} CPU-s per hour of data), wall {s['wall_s']:.1f} s")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(figures, f, indent=1)


if __name__ == "__main__":
    main()
