#!/usr/bin/env python3
"""Wall and CPU time of `plsa diagnose` on three 60 s runs, per withheld effect (bench/README.md, "Diagnosis").

The runs come from the independently written simulator of `plsa
diagnose-selfcheck` (laws outside every candidate's family, nominal physics
randomised): one case per effect and one with nothing withheld (seeds
--seed .. --seed + 7, the self-check's numbering), each a 120 s training run
cut in two and a 60 s held-out run, recorded from rest. Each case's
diagnosis (defaults, every effect a candidate, nominal physics plsa's
defaults with every effect off: `plsa sim-config`) runs as its own process,
with the identified reference (the default) and without it
(--no-identified-reference), --repeats times each; the median wall time and
CPU time (user + system, every thread, from wait4's rusage) are printed with
the effects it selected; --json FILE writes them.

--against OTHER_BUILD measures a change: every diagnosis is also run by that
build's plsa, the two in turn (this build first) --repeats times each, so
that both meet the same load on a shared host; each mode then carries the
other build's medians and the ratio of this build's to them. --cases NAMES
keeps only the cases whose names contain one of NAMES (comma-separated,
e.g. pneumatic_lag,null). --against-flags FLAGS: the other diagnoses also
take these flags (e.g. "--calibration-integrator euler"); without
--against, the other build is this one, so one build measures an option;
--flags FLAGS: this build's diagnoses take these.

Usage: python3 bench/diagnose_cost.py [--build build] [--seed 1] [--repeats 1] [--against build]
                                      [--flags FLAGS] [--against-flags FLAGS] [--cases NAMES]
                                      [--json FILE]
"""
import argparse
import glob
import json
import os
import shlex
import statistics
import subprocess
import sys
import tempfile

from bench_process import default_build, measured, plsa_exe


def say(text):
    print(text, file=sys.stderr, flush=True)


def nominal_config(exe, path):
    """The simulator's defaults with every effect off, written to path; the effects' names."""
    subprocess.run([exe, "sim-config", "--out", path], check=True, stdout=subprocess.DEVNULL)
    with open(path) as f:
        config = json.load(f)
    effects = [name for name, entry in config.items() if isinstance(entry, dict) and "enabled" in entry]
    for name in effects:
        config[name]["enabled"] = False
    with open(path, "w") as f:
        json.dump(config, f)
    return effects


def split_training(train, first, second):
    """The training run's first and second halves as two runs, the second's time restarted at 0."""
    with open(train) as f:
        lines = f.read().splitlines()
    head = next(i for i, line in enumerate(lines) if not line.startswith("#")) + 1
    body = lines[head:]
    half = len(body) // 2
    t0 = float(body[half].split(",", 1)[0])
    retimed = [repr(float(line.split(",", 1)[0]) - t0) + "," + line.split(",", 1)[1] for line in body[half:]]
    for path, rows in ((first, body[:half]), (second, retimed)):
        with open(path + ".part", "w") as f:
            f.write("\n".join(lines[:head] + rows) + "\n")
        os.replace(path + ".part", path)


def record_cases(exe, tmp, seed, effects):
    """Runs of one case per effect (the self-check's default: every effect) and a null case;
    {case name: (training csv, held-out csv)}."""
    runs = os.path.join(tmp, "runs")
    os.mkdir(runs)
    cmd = [exe, "diagnose-selfcheck", "--seeds", "1", "--no-pairs", "--null", "1", "--seed", str(seed),
           "--train-s", "120", "--heldout-s", "60", "--save-runs", runs]
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode not in (0, 1):  # 1: the self-check's targets not met, which is not this bench's question
        raise SystemExit(f"diagnose_cost: {' '.join(cmd)} exited with {done.returncode}:\n{done.stderr}")
    cases = {}
    for train in sorted(glob.glob(os.path.join(runs, "*_train.csv"))):
        name = os.path.basename(train)[:-len("_train.csv")]
        cases[name] = (train, train[:-len("_train.csv")] + "_heldout.csv")
    if len(cases) != len(effects) + 1:
        raise SystemExit(f"diagnose_cost: expected {len(effects) + 1} cases in {runs}, found {sorted(cases)}")
    return cases


def summary(times, out):
    """Median CPU and wall seconds of `times` and what the diagnosis written to `out` found."""
    with open(os.path.join(out, "diagnosis.json")) as f:
        d = json.load(f)
    return {"cpu_s": statistics.median(t[0] for t in times), "wall_s": statistics.median(t[1] for t in times),
            "selected": d["selected"],
            "reference_gap_percent": d["identified_reference"]["heldout_gap_percent"]
            if d["identified_reference"]["available"] else None,
            "gap_after_percent": d["gap_after"], "calibration_step_s": d["calibration_step_s"],
            "calibration_step_trials": d.get("calibration_step_trials", [])}


def diagnose_case(exes, tmp, sims, name, train, heldout, repeats):
    """Per mode (with and without the identified reference): median CPU s, median wall s, what was selected;
    with a second (plsa, flags) in `exes`, its figures as "against" and the ratios, the two run in turn."""
    run1, run2 = os.path.join(tmp, name + "_run1.csv"), os.path.join(tmp, name + "_run2.csv")
    split_training(train, run1, run2)
    result = {}
    for mode, extra in (("with_reference", []), ("without_reference", ["--no-identified-reference"])):
        outs = [os.path.join(tmp, f"{name}_{mode}_{k}") for k in range(len(exes))]
        times = [[] for _ in exes]
        for _ in range(repeats):
            for k, (exe, flags) in enumerate(exes):
                cmd = [exe, "diagnose", "--sim", sims[k], "--real", run1, "--real", run2, "--real", heldout,
                       "--out", outs[k]] + extra + flags
                times[k].append(measured(cmd, "diagnose_cost")[1:])
        result[mode] = summary(times[0], outs[0])
        if len(exes) > 1:
            other = summary(times[1], outs[1])
            result[mode]["against"] = other
            result[mode]["wall_ratio"] = result[mode]["wall_s"] / other["wall_s"]
            result[mode]["cpu_ratio"] = result[mode]["cpu_s"] / other["cpu_s"]
    return result


def line(mode, m):
    """One mode's figures as printed (with --against, the other build's and the ratio)."""
    text = (f"{mode.replace('_', ' ')} wall {m['wall_s']:.1f} s, CPU {m['cpu_s']:.1f} s, selected "
            f"{'+'.join(m['selected']) or 'nothing'}")
    if "against" in m:
        o = m["against"]
        text += (f" (against: wall {o['wall_s']:.1f} s, CPU {o['cpu_s']:.1f} s, selected "
                 f"{'+'.join(o['selected']) or 'nothing'}; ratio wall {m['wall_ratio']:.2f}, CPU {m['cpu_ratio']:.2f})")
    return text


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=default_build())
    ap.add_argument("--seed", type=int, default=1, help="the first case's seed (default 1)")
    ap.add_argument("--repeats", type=int, default=1, help="diagnoses per case and mode (default 1; the median is kept)")
    ap.add_argument("--against", metavar="BUILD", help="another build whose plsa runs every diagnosis too, in turn")
    ap.add_argument("--flags", default="", metavar="FLAGS", help="flags this build's diagnoses take")
    ap.add_argument("--against-flags", default="", metavar="FLAGS",
                    help="flags the other build's diagnoses also take (without --against: this build)")
    ap.add_argument("--cases", help="only the cases whose names contain one of these (comma-separated)")
    ap.add_argument("--json", metavar="FILE", help="write the figures here")
    a = ap.parse_args()
    if a.repeats < 1:
        raise SystemExit("diagnose_cost: --repeats must be at least 1")
    exes = [(plsa_exe(a.build, "diagnose_cost"), shlex.split(a.flags))]
    if a.against or a.against_flags:
        exes.append((plsa_exe(a.against or a.build, "diagnose_cost"), shlex.split(a.against_flags)))
    wanted = [w for w in (a.cases or "").split(",") if w]
    figures = {"seed": a.seed, "repeats": a.repeats, "flags": a.flags, "cases": []}
    if len(exes) > 1:
        figures["against"] = os.path.abspath(a.against or a.build)
        figures["against_flags"] = a.against_flags
    with tempfile.TemporaryDirectory() as tmp:
        # Each build's own configuration file (an older build refuses a newer one's keys).
        sims = [os.path.join(tmp, f"sim_all_off_{k}.json") for k in range(len(exes))]
        effects = [nominal_config(exe, path) for (exe, _), path in zip(exes, sims)][0]
        cases = record_cases(exes[0][0], tmp, a.seed, effects)
        chosen = {n: c for n, c in cases.items() if not wanted or any(w in n for w in wanted)}
        if not chosen:
            raise SystemExit(f"diagnose_cost: no case matches --cases {a.cases}; the cases: {', '.join(cases)}")
        for name, (train, heldout) in chosen.items():
            say(f"diagnose_cost: {name}")
            figures["cases"].append({"case": name, **diagnose_case(exes, tmp, sims, name, train, heldout, a.repeats)})
    for c in figures["cases"]:
        print(c["case"] + ": " + "; ".join(line(mode, c[mode]) for mode in ("with_reference", "without_reference")))
    if a.json:
        with open(a.json + ".part", "w") as f:
            json.dump(figures, f, indent=1)
        os.replace(a.json + ".part", a.json)


if __name__ == "__main__":
    main()
