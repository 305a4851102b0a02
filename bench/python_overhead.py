#!/usr/bin/env python3
"""What the Python module adds to a predict call (bench/README.md, "From Python").

Identifies a model from Python as a user would (the built-in simulator's grid
run, input-side scheduling), feeds the predictor the joystick run, then, on
the same state and plan, times `Predictor.predict(80, plan)` from Python
(each call on its own, time.perf_counter_ns) and the C++ call underneath
(`_time_predict`, each call timed in C++), held and planned. Prints the p50s
and their difference; --json FILE writes them.

Usage: PYTHONPATH=build/python python3 bench/python_overhead.py [--calls N] [--json FILE]
"""
import argparse
import json
import os
import statistics
import tempfile
import time

import numpy as np

import plsa


def python_p50(call, calls):
    ns = []
    for _ in range(calls):
        t0 = time.perf_counter_ns()
        call()
        ns.append(time.perf_counter_ns() - t0)
    return statistics.median(ns)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=20000, help="calls per figure (default 20000)")
    ap.add_argument("--json", metavar="FILE", help="write the figures here")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        train, run = os.path.join(tmp, "train.csv"), os.path.join(tmp, "run.csv")
        plsa.simulate("grid2", train, seed=1)
        plsa.simulate("joystick", run, seed=2, duration_s=30)
        model = plsa.identify([train], scheduling="input")
        data = plsa.read_log(run)
    u = np.column_stack([data[c] for c in model.inputs])
    y = np.column_stack([data[c] for c in model.outputs])
    p = plsa.Predictor(model)
    for k in range(800):
        p.update(data["time_s"][k], u[k], y[k])
    plan = np.ascontiguousarray(u[801:880])
    held = np.zeros((0, u.shape[1]))
    figures = {}
    for name, rows in (("held", held), ("planned", plan)):
        cxx = p._time_predict(80, rows, a.calls)
        py = python_p50(lambda: p.predict(80, rows), a.calls)
        figures[name] = {"python_p50_ns": py, "cxx_p50_ns": cxx, "overhead_ns": py - cxx}
        print(f"predict 80, {name}: Python {py:.0f} ns, C++ {cxx:.0f} ns (p50 of {a.calls} calls each): "
              f"Python adds {py - cxx:.0f} ns", flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"calls": a.calls, "predict_80": figures}, f, indent=1)


if __name__ == "__main__":
    main()
