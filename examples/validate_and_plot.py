"""Validate a model on a log and plot what was scored: measured, k steps ahead
and free simulation, per output, with the residuals under them.

    python3 examples/validate_and_plot.py MODEL.json RUN.csv plot.png [--horizon 80]
    python3 examples/validate_and_plot.py --simulated plot.png    # no data of your own:
        the built-in simulated actuator's grid run to identify on, a joystick run to validate on
"""
import argparse
import os
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt
import numpy as np

import plsa


def simulated_model_and_run(folder):
    train, run = os.path.join(folder, "train.csv"), os.path.join(folder, "val.csv")
    plsa.simulate("grid2", train, seed=1)
    plsa.simulate("joystick", run, seed=2, duration_s=40)
    return plsa.identify([train], progress=lambda line: print(line, file=sys.stderr)), run


def plot(model, run, horizon, out):
    v = plsa.validate(model, run, horizons=[horizon])
    data = plsa.read_log(run)
    t = data["time_s"] if "time_s" in data else np.arange(len(v[model.outputs[0]]["measured"])) * model.sample_time_s
    fig, axes = plt.subplots(2, len(model.outputs), figsize=(6 * len(model.outputs), 6), sharex=True,
                             gridspec_kw={"height_ratios": [3, 1]}, squeeze=False)
    for c, name in enumerate(model.outputs):
        o = v[name]
        s = o["scored_from"]
        top, bottom = axes[0][c], axes[1][c]
        top.plot(t, o["measured"], color="black", label="measured")
        top.plot(t, o["predicted"][horizon], color="tab:blue",
                 label=f"{horizon} steps ahead (fit {o['fit'][horizon]:.1f}%)")
        top.plot(t, o["simulated"], color="tab:red", linestyle="--", label=f"simulation (fit {o['fit_sim']:.1f}%)")
        top.axvspan(t[0], t[s], color="0.9", label="not scored")
        top.set_ylabel(name)
        top.legend(fontsize="small")
        bottom.plot(t, o["measured"] - o["predicted"][horizon], color="tab:blue")
        bottom.plot(t, o["measured"] - o["simulated"], color="tab:red", linestyle="--")
        bottom.axhline(0.0, color="black", linewidth=0.5)
        bottom.set_ylabel("residual")
        bottom.set_xlabel("time (s)")
        if o["sim_departure"] is not None:
            print(f"warning: the free simulation of {name} leaves the measured range: {o['sim_departure']}",
                  file=sys.stderr)
    fig.tight_layout()
    partial = out + ".partial.png"  # written whole, then renamed: never a half-written plot
    fig.savefig(partial, dpi=100)
    os.replace(partial, out)
    return v


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+", help="MODEL RUN OUT, or OUT with --simulated")
    ap.add_argument("--simulated", action="store_true", help="identify and validate on the simulated actuator")
    ap.add_argument("--horizon", type=int, default=80, help="steps ahead to plot (default 80)")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        if a.simulated:
            if len(a.files) != 1:
                ap.error("--simulated takes one file: the plot")
            (out,) = a.files
            model, run = simulated_model_and_run(tmp)
        else:
            if len(a.files) != 3:
                ap.error("give MODEL RUN OUT")
            model_path, run, out = a.files
            if os.path.abspath(out) in (os.path.abspath(model_path), os.path.abspath(run)):
                ap.error(f"the plot would overwrite an input: {out}")
            model = plsa.Model.load(model_path)
        v = plot(model, run, a.horizon, out)
    for name in model.outputs:
        print(f"{name}: {a.horizon}-step fit {v[name]['fit'][a.horizon]:.1f}%, simulation {v[name]['fit_sim']:.1f}%")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
