#!/usr/bin/env python3
"""Memory and CPU time of identification and validation on a long log (bench/README.md, "Offline").

Records a joystick run of the built-in simulator (default an hour at 80 Hz,
from rest, every effect on), then runs `plsa identify` with the demo's
options (input-side scheduling, the sensor's drift asked for), the same with the structure search on every
sample (--search-samples 0) instead of its default sample, and `plsa
validate` of the first model on the same log, each as its own process
--repeats times (default 3), and reads each one's peak resident memory and
CPU time (user + system, every thread) from the kernel (wait4's rusage).
Prints per step the median CPU and wall time of its runs and the largest
peak memory, per sample and per hour of data, then both models' fits on a
new 10 min joystick run (another seed); --json FILE writes them, each run's
CPU time too.

Usage: python3 bench/offline_cost.py [--build build] [--minutes 60] [--repeats 3] [--json FILE]
"""
import argparse
import json
import os
import statistics
import subprocess
import tempfile

from bench_process import default_build, measured, plsa_exe


def new_run_fits(exe, tmp, models):
    """Each model's validate fits (per output: fit_k40, fit_k80, fit_sim) on a new 10 min joystick run."""
    log = os.path.join(tmp, "new_run.csv")
    subprocess.run([exe, "simulate", "--experiment", "joystick", "--duration", "600", "--seed", "7", "--out", log],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    fits = {}
    for name, model in models.items():
        out = subprocess.run([exe, "validate", "--model", model, "--log", log, "--json", "-"], check=True,
                             capture_output=True, text=True).stdout
        fits[name] = {o: {k: f[k] for k in ("fit_k40", "fit_k80", "fit_sim")}
                      for o, f in json.loads(out)["outputs"].items()}
    return fits


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=default_build())
    ap.add_argument("--minutes", type=float, default=60.0, help="length of the recorded run (default 60)")
    ap.add_argument("--repeats", type=int, default=3,
                    help="runs of each step; the median CPU and wall time are reported (default 3)")
    ap.add_argument("--json", metavar="FILE", help="write the figures here")
    a = ap.parse_args()
    if a.repeats < 1:
        ap.error("--repeats must be at least 1")
    exe = plsa_exe(a.build, "offline_cost")
    figures = {"minutes": a.minutes, "repeats": a.repeats, "steps": {}}
    with tempfile.TemporaryDirectory() as tmp:
        log, model = os.path.join(tmp, "run.csv"), os.path.join(tmp, "model.json")
        subprocess.run([exe, "simulate", "--experiment", "joystick", "--duration", str(a.minutes * 60), "--seed", "6",
                        "--out", log], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(log) as f:
            samples = sum(1 for _ in f) - 1
        figures["samples"] = samples
        hours = samples / 80.0 / 3600.0
        every = os.path.join(tmp, "model_every_sample.json")
        identify = [exe, "identify", "--log", log, "--scheduling", "input", "--output-drift", "auto", "--out"]
        steps = {"identify": identify + [model],
                 "identify, search on every sample": identify + [every, "--search-samples", "0"],
                 "validate": [exe, "validate", "--model", model, "--log", log]}
        for name, cmd in steps.items():
            runs = [measured(cmd, "offline_cost") for _ in range(a.repeats)]
            kb = max(r[0] for r in runs)
            cpu = statistics.median(r[1] for r in runs)
            figures["steps"][name] = {"peak_kb": kb, "kb_per_sample": kb / samples, "cpu_s": cpu,
                                      "cpu_s_per_hour": cpu / hours,
                                      "wall_s": statistics.median(r[2] for r in runs),
                                      "cpu_s_runs": [r[1] for r in runs]}
        figures["new_run_fits"] = new_run_fits(exe, tmp, {"identify": model,
                                                          "identify, search on every sample": every})
    print(f"{samples} samples ({a.minutes:g} min at 80 Hz)")
    for name, s in figures["steps"].items():
        print(f"{name}: peak {s['peak_kb'] / 1024:.0f} MB ({s['kb_per_sample']:.2f} KB per sample), "
              f"CPU {s['cpu_s']:.1f} s median of {a.repeats} ({s['cpu_s_per_hour']:.0f} CPU-s per hour of data; "
              f"runs {', '.join(f'{c:.1f}' for c in s['cpu_s_runs'])}), wall {s['wall_s']:.1f} s")
    for name, outs in figures["new_run_fits"].items():
        print(f"{name}, on a new 10 min run: " + ", ".join(
            f"{o} k=40 {f['fit_k40']:.1f} sim {f['fit_sim']:.1f}" for o, f in outs.items()))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(figures, f, indent=1)


if __name__ == "__main__":
    main()
