#!/usr/bin/env python3
"""Each of identify's structure knobs left out, on physics plsa did not write.

The runs come from `plsa generalise --save-runs DIR` (the independent
actuator, every case and seed, recorded from rest): per row the grid run
trains and the joystick run validates. Each configuration is `plsa identify`
with its defaults but one candidate family left out ('0' alone, or off), so
a knob that cross-validation keeps but that does not pay on the held-out
joystick run shows up as a row where leaving it out fits better; "output
drift" instead asks for the drift stage, off by default, and a row whose
stage leaves the drift in counts as the defaults' model.
"fractions on increments" fits the tied slow fractions on the output
increments alone instead of stepping them on the simulated level.

Usage: bench/knob_ablation.py --runs DIR [--plsa build/apps/plsa]
       [--jobs 2] [--json OUT] [--keep DIR] [--only NAME ...]
Prints, per configuration, the mean held-out fits (40 / 80 steps /
simulated, bending then steering; validate's scoring window, the same
samples for every configuration of a row) and the rows where leaving the
knob out moves the mean of the six fits by more than one point either way.
"""
import argparse
import concurrent.futures
import glob
import json
import os
import re
import subprocess
import sys
import tempfile

# Name -> the identify arguments that leave one knob's candidates out (or,
# for the sensor drift, off by default, ask for it).
CONFIGURATIONS = {
    "defaults": [],
    "no play channels": ["--play", "0", "--play-bank", "none"],
    "no play bank": ["--play-bank", "none"],
    "no play coupling": ["--play-coupling", "0"],
    "no play threshold": ["--play-threshold", "0"],
    "no schedule lag": ["--schedule-lag", "0"],
    "no slow pole": ["--slow-pole", "0"],
    "output drift": ["--output-drift", "auto"],
    "fractions on increments": ["--slow-fraction-fit", "increments"],
}
OUTPUTS = ("bend_deg", "steer_deg")
FITS = ("fit_k40", "fit_k80", "fit_sim")
# What the model file says each knob chose.
CHOSEN = ("input_play", "play_coupling", "play_threshold", "schedule_lag_s", "training_output_drift")


def rows_of(runs):
    """(row name, grid run, joystick run) for every saved row."""
    rows = []
    for grid in sorted(glob.glob(os.path.join(runs, "*_grid2.csv"))):
        stem = grid[: -len("_grid2.csv")]
        joystick = stem + "_joystick.csv"
        if os.path.exists(joystick):
            rows.append((os.path.basename(stem), grid, joystick))
    if not rows:
        sys.exit("knob_ablation: no *_grid2.csv with its *_joystick.csv in " + runs)
    return rows


def fit_one(plsa, workdir, row, config):
    """One row under one configuration: its fits and what the model chose.
    A model already in workdir with its progress log is reused."""
    name, grid, joystick = row
    stem = os.path.join(workdir, name + "." + config.replace(" ", "_"))
    model, log = stem + ".json", stem + ".log"
    if not (os.path.exists(model) and os.path.exists(log)):
        progress = subprocess.run([plsa, "identify", "--log", grid, "--inputs", "p_1,p_2,p_3", "--outputs",
                                   ",".join(OUTPUTS), "--out", model] + CONFIGURATIONS[config],
                                  check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True).stderr
        with open(log + ".tmp", "w") as f:
            f.write(progress)
        os.replace(log + ".tmp", log)
    with open(log) as f:
        progress = f.read()
    out = subprocess.run([plsa, "validate", "--model", model, "--log", joystick, "--horizons", "40,80", "--json", "-"],
                         check=True, capture_output=True, text=True).stdout
    fits = json.loads(out)["outputs"]
    with open(model) as f:
        m = json.load(f)
    chosen = {k: m[k] for k in CHOSEN if k in m}
    slow = [line for line in progress.splitlines() if "[5/5] slow pole" in line]
    found = re.search(r"kept [0-9.]+ s|none kept", slow[0]) if slow else None
    chosen["slow_pole"] = found.group(0) if found else "not searched"
    return {"fits": [fits[o][k] for o in OUTPUTS for k in FITS], "chosen": chosen}


def unchanged_by(config, chosen):
    """Whether leaving the knob out cannot change the row's model: the
    defaults' search already chose the value the configuration leaves (each
    stage keeps its best candidate, so removing losing candidates leaves the
    choice; --exhaustive identifies anyway, to check this)."""
    if config == "no play channels":
        return all(channel == 0.0 for channels in chosen["input_play"] for channel in channels)
    if config == "no play bank":
        return all(len(channels) == 1 for channels in chosen["input_play"])
    if config == "no play coupling":
        return chosen.get("play_coupling", 0.0) == 0.0
    if config == "no play threshold":
        return chosen.get("play_threshold", 0.0) == 0.0
    if config == "no schedule lag":
        return chosen.get("schedule_lag_s", 0.0) == 0.0
    if config in ("no slow pole", "fractions on increments"):
        return chosen["slow_pole"] in ("none kept", "not searched")
    return False  # "output drift" adds a stage the defaults do not run


def run_jobs(pool, plsa, workdir, jobs, results):
    """Identifies and validates every (row, configuration) in jobs, with progress."""
    futures = {pool.submit(fit_one, plsa, workdir, row, c): (row[0], c) for row, c in jobs}
    for done, fut in enumerate(concurrent.futures.as_completed(futures), 1):
        name, c = futures[fut]
        results[c][name] = fut.result()
        print("[%d/%d] %s: %s" % (done, len(jobs), c, name), file=sys.stderr, flush=True)


def summary(results, configs):
    """Per configuration: mean fits, and rows moved by more than a point against the defaults."""
    lines = []
    base = results["defaults"]
    for c in configs:
        rows = results[c]
        n = len(rows)
        mean = [sum(r["fits"][i] for r in rows.values()) / n for i in range(6)]
        line = "%-24s %5.1f / %5.1f / %6.1f   %5.1f / %5.1f / %6.1f" % ((c,) + tuple(mean))
        if c != "defaults":
            delta = {k: sum(rows[k]["fits"]) / 6 - sum(base[k]["fits"]) / 6 for k in rows}
            better = sorted(k for k, d in delta.items() if d > 1.0)
            worse = sorted(k for k, d in delta.items() if d < -1.0)
            same = sum(1 for r in rows.values() if r.get("same_as_defaults"))
            line += "   against the defaults: better in %d rows, worse in %d (of %d; %d the defaults' model)" % (
                len(better), len(worse), n, same)
            if better:
                line += "\n" + " " * 26 + "better: " + ", ".join("%s %+.1f" % (k, delta[k]) for k in better)
        lines.append(line)
    return "\n".join(lines)


def markdown_table(results, configs):
    """docs/generalisation.md's table: per configuration the rows whose defaults kept the knob (the rows
    it can change), the mean change of each fit there against the defaults, and the rows whose mean of
    the six fits moves by more than a point either way."""
    lines = ["| configuration | `identify` option | rows it can change | change of the fits against the defaults "
             "| rows better / worse than the defaults |", "| --- | --- | --- | --- | --- |"]
    base = results["defaults"]
    for c in configs[1:]:
        kept = [k for k, r in results[c].items() if not r.get("same_as_defaults")]
        if not kept:
            continue
        change = [sum(results[c][k]["fits"][i] - base[k]["fits"][i] for k in kept) / len(kept) for i in range(6)]
        delta = [sum(results[c][k]["fits"]) / 6 - sum(base[k]["fits"]) / 6 for k in kept]
        fits = " / ".join("%+.1f" % x for x in change[:3]) + ", " + " / ".join("%+.1f" % x for x in change[3:])
        lines.append("| %s | `%s` | %d | %s | %d / %d |" % (
            c, " ".join(CONFIGURATIONS[c]), len(kept), fits,
            sum(1 for d in delta if d > 1.0), sum(1 for d in delta if d < -1.0)))
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", required=True, help="plsa generalise --save-runs directory")
    ap.add_argument("--plsa", default=os.path.join(os.path.dirname(__file__), "..", "build", "apps", "plsa"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json", help="write every row's fits and choices here")
    ap.add_argument("--keep", help="keep the models and identify's progress here; a rerun reuses them")
    ap.add_argument("--exhaustive", action="store_true",
                    help="identify every row under every configuration, also where the defaults chose the value left")
    ap.add_argument("--only", nargs="*", choices=list(CONFIGURATIONS), help="configurations (defaults always run)")
    a = ap.parse_args()
    configs = ["defaults"] + [c for c in (a.only or CONFIGURATIONS) if c != "defaults"]
    rows = rows_of(a.runs)
    results = {c: {} for c in configs}
    with tempfile.TemporaryDirectory() as tmp, concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        workdir = a.keep or tmp
        os.makedirs(workdir, exist_ok=True)
        run_jobs(pool, a.plsa, workdir, [(row, "defaults") for row in rows], results)
        jobs = []
        for c in configs[1:]:
            for row in rows:
                if a.exhaustive or not unchanged_by(c, results["defaults"][row[0]]["chosen"]):
                    jobs.append((row, c))
                else:
                    results[c][row[0]] = dict(results["defaults"][row[0]], same_as_defaults=True)
        run_jobs(pool, a.plsa, workdir, jobs, results)
        # Asked for, a drift the stage leaves in leaves the defaults' model.
        for name, r in results.get("output drift", {}).items():
            if "training_output_drift" not in r["chosen"]:
                r["same_as_defaults"] = True
    print("%d rows; mean held-out fit, bending then steering (40 / 80 steps / simulated)" % len(rows))
    print(summary(results, configs))
    print()
    print(markdown_table(results, configs))
    if a.json:
        tmp = a.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump(results, f, indent=1)
        os.replace(tmp, a.json)


if __name__ == "__main__":
    main()
