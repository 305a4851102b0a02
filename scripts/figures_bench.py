"""The bench figure blocks of scripts/plsa-figures (bench/README.md): per call, the 80 Hz loop,
Google Benchmark, Python's overhead, offline cost, the diagnosis's time, and the demo model against the predictor's
targets."""
import json
import math
import os
import re
import statistics
import sys
import tempfile


from figures_common import HERE, replace_block, run, say, stamp


def fmt(ns):
    if ns < 1000:
        return f"{ns:.0f} ns"
    us = ns / 1000.0
    if us >= 1000:
        return f"{us / 1000.0:.2f} ms"
    return f"{us:.2f} us" if us < 10 else f"{us:.1f} us" if us < 100 else f"{us:.0f} us"


def pair(lat, key):
    v = lat.get(key)
    return "-" if v is None else f"{fmt(v['p50'])} / {fmt(v['p99_9'])}"


def bench_tables(build, calls, dry_run):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "latency.json")
        text = run([os.path.join(build, "bench", "plsa-bench"), "--latency", "--calls", str(calls), "--json", out])
        with open(out) as f:
            data = json.load(f)
    lat = data["latency_ns"]
    models = [m.group(1) for m in re.finditer(r"^([^ \n][^:\n]*): \d+ in, ", text, re.M)]
    rows = ["| model | update | predict 80 held | predict 80 planned | predict 400 held | sensitivity 80 | "
            "predict 80 / 400 after a 125 s hold (p50) |", "| --- | --- | --- | --- | --- | --- | --- |"]
    for m in models:
        held80, held400 = lat.get(f"{m}: predict 80, after a 125 s hold"), lat.get(f"{m}: predict 400, after a 125 s hold")
        after = "-" if not held80 or not held400 else f"{fmt(held80['p50'])} / {fmt(held400['p50'])}"
        cells = [pair(lat, f"{m}: update"), pair(lat, f"{m}: predict 80, input held, moving"),
                 pair(lat, f"{m}: predict 80, planned input"), pair(lat, f"{m}: predict 400, input held, moving"),
                 pair(lat, f"{m}: sensitivity 80 (jacobian to the plan)"), after]
        rows.append(f"| {m} | " + " | ".join(cells) + " |")
    command = f"plsa-bench --latency --calls {calls}"
    realtime = next((l.split(": ", 1)[1] for l in text.splitlines() if l.startswith("real time: ")), "not asked")
    fixed = [f"{k[len('fixed work of '):]}: {pair(lat, k)}" for k in sorted((k for k in lat if k.startswith("fixed work of about ")), key=lambda k: lat[k]["p50"])]
    machine_line = ("\nThe machine's own tail, same run (a fixed amount of arithmetic per call, timed alike): "
                    + "; ".join(fixed) + ".\n") if fixed else ""
    agree = [v for k, v in data["figures"].items() if k.endswith("largest difference to the straightforward implementation")]
    if agree:
        machine_line += (f"\nEvery model's predictions agree with the straightforward implementation to {max(agree):.1e} "
                         "(output units) or better.\n")
    replace_block(os.path.join(HERE, "bench", "README.md"), "bench-per-call",
                  stamp(command) + f" Real time: {realtime}.\n\n" + "\n".join(rows) + "\n" + machine_line, dry_run)
    seg = ["| segments | p50 | p99.9 | p99.9 as a share of the 12.5 ms period |", "| --- | --- | --- | --- |"]
    for key in sorted((k for k in lat if k.endswith("segments of the demo's model: update + predict 80 per tick")),
                      key=lambda k: int(k.split()[0])):
        v = lat[key]
        seg.append(f"| {key.split()[0]} | {fmt(v['p50'])} | {fmt(v['p99_9'])} | {100 * v['p99_9'] / 12.5e6:.1f}% |")
    replace_block(os.path.join(HERE, "bench", "README.md"), "bench-segments",
                  stamp(command) + "\n\n" + "\n".join(seg) + "\n", dry_run)
    fast = ["| model | straightforward planned / held | plsa, planned | plsa, held | speed-up planned / held |",
            "| --- | --- | --- | --- | --- |"]
    for m in models:
        sp, sh = lat.get(f"{m}: straightforward update + predict 80, planned"), lat.get(
            f"{m}: straightforward update + predict 80, held")
        up, hp = data["figures"].get(f"{m}: speed-up over straightforward, planned (p50)"), data["figures"].get(
            f"{m}: speed-up over straightforward, held (p50)")
        if not (sp and sh and up and hp):
            continue
        fast.append(f"| {m} | {fmt(sp['p50'])} / {fmt(sh['p50'])} | {fmt(sp['p50'] / up)} | {fmt(sh['p50'] / hp)} | "
                    f"{up:.0f}x / {hp:.0f}x |")
    replace_block(os.path.join(HERE, "bench", "README.md"), "bench-straightforward",
                  stamp(command) + "\n\n" + "\n".join(fast) + "\n", dry_run)
    replace_block(os.path.join(HERE, "bench", "README.md"), "bench-targets",
                  stamp(command) + "\n\n" + targets_table(lat, data["figures"]) + "\n", dry_run)
    return lat


def bench_loop(build, lat, dry_run):
    """The 80 Hz loop: wake-up jitter, work per tick and misses; per segment against the tight loop's figure
    (from `lat`, the latency run's, when there is one)."""
    command = "plsa-bench --loop 20 --segments 100"
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "loop.json")
        text = run([os.path.join(build, "bench", "plsa-bench"), "--loop", "20", "--segments", "100", "--json", out])
        with open(out) as f:
            data = json.load(f)
    setup = next((l.split("; ", 1)[1] for l in text.splitlines() if l.startswith("plsa-bench loop:")), "?")
    jit, work, fig = data["latency_ns"]["loop wake-up jitter"], data["latency_ns"]["loop work per tick"], data["figures"]
    ticks, segments, period = int(fig["loop ticks"]), int(fig["loop segments"]), 12.5e6
    rows = ["| ticks | wake-up jitter p50 / p99.9 | work per tick p50 / p99.9 | share of the period p50 / p99.9 | "
            "deadline misses |", "| --- | --- | --- | --- | --- |",
            f"| {ticks} | {fmt(jit['p50'])} / {fmt(jit['p99_9'])} | {fmt(work['p50'])} / {fmt(work['p99_9'])} | "
            f"{100 * work['p50'] / period:.0f}% / {100 * work['p99_9'] / period:.0f}% | {fig['loop deadline misses']:.0f} |"]
    body = (stamp(command) + f" Each tick updates {segments} segments of the demo's model and predicts 80 steps with "
            f"each (input held). Real time: {setup}.\n\n" + "\n".join(rows) + "\n")
    tight = (lat or {}).get(f"{segments} segments of the demo's model: update + predict 80 per tick")
    if tight:
        body += (f"\nPer tick that is {work['p50'] / tight['p50']:.1f}x the tight loop's {fmt(tight['p50'])} (p50, "
                 "the per-call run above).\n")
    replace_block(os.path.join(HERE, "bench", "README.md"), "bench-loop", body, dry_run)


def build_python(build):
    """The interpreter the build's Python module is for (CMakeCache's Python3_EXECUTABLE)."""
    try:
        with open(os.path.join(build, "CMakeCache.txt")) as f:
            for line in f:
                if line.startswith("Python3_EXECUTABLE:"):
                    return line.split("=", 1)[1].strip()
    except OSError:
        pass
    return "/usr/bin/python3"


def bench_python(build, dry_run):
    """What the Python module adds to a predict call, against the C++ call on the same state."""
    if not os.path.isdir(os.path.join(build, "python", "plsa")):
        say("bench-python: no Python module in the build; skipped")
        return
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "python.json")
        env = dict(os.environ, PYTHONPATH=os.path.join(build, "python"))
        run([build_python(build), os.path.join(HERE, "bench", "python_overhead.py"), "--json", out], env=env)
        with open(out) as f:
            data = json.load(f)
    rows = ["| predict 80 | from Python (p50) | the C++ call (p50) | Python adds |", "| --- | --- | --- | --- |"]
    for name, v in data["predict_80"].items():
        rows.append(f"| {name} | {fmt(v['python_p50_ns'])} | {fmt(v['cxx_p50_ns'])} | {fmt(v['overhead_ns'])} |")
    replace_block(os.path.join(HERE, "bench", "README.md"), "bench-python",
                  stamp("bench/python_overhead.py") + f" {data['calls']} calls each.\n\n" + "\n".join(rows) + "\n",
                  dry_run)


def bench_script(build, script):
    """The figures a bench/ script writes with --json, from one run of it."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "figures.json")
        run([sys.executable, os.path.join(HERE, "bench", script), "--build", build, "--json", out])
        with open(out) as f:
            return json.load(f)


def bench_offline(build, dry_run):
    """Peak memory and CPU time of identify and validate on an hour of 80 Hz data, against the offline targets."""
    data = bench_script(build, "offline_cost.py")
    repeats = data.get("repeats", 1)
    rows = [f"Each step run {repeats} times: the largest peak memory, the median CPU time (every run's in brackets).",
            "", "| step | peak memory | per sample (target <= 1 KB) | CPU time | per hour of data (target <= 20 s) |",
            "| --- | --- | --- | --- | --- |"]
    for name, s in data["steps"].items():
        verdict = "met" if s["kb_per_sample"] <= 1.0 else "not met"
        cpu_verdict = "" if name != "identify" else (" (met)" if s["cpu_s_per_hour"] <= 20 else " (not met)")
        runs = ", ".join(f"{c:.1f}" for c in s.get("cpu_s_runs", [s["cpu_s"]]))
        rows.append(f"| {name} | {s['peak_kb'] / 1024:.0f} MB | {s['kb_per_sample']:.2f} KB ({verdict}) | "
                    f"{s['cpu_s']:.1f} s ({runs}) | {s['cpu_s_per_hour']:.1f} s{cpu_verdict} |")
    rows += ["", "The two models on a new 10 min joystick run (seed 7), fit % (`plsa validate`):", "",
             "| model | output | k=40 | k=80 | simulation |", "| --- | --- | --- | --- | --- |"]
    for name, outs in data["new_run_fits"].items():
        rows += [f"| {name} | {o} | {f['fit_k40']:.1f} | {f['fit_k80']:.1f} | {f['fit_sim']:.1f} |"
                 for o, f in outs.items()]
    replace_block(os.path.join(HERE, "bench", "README.md"), "bench-offline",
                  stamp("bench/offline_cost.py") + f" {data['samples']} samples ({data['minutes']:g} min at 80 Hz)."
                  "\n\n" + "\n".join(rows) + "\n", dry_run)


def case_name(saved):
    """A self-check case's saved-run name as its table names it: hysteresis__bouc_wen___2 -> hysteresis (bouc_wen) #2."""
    head, _, number = saved.rpartition("_")
    head = head.rstrip("_")
    effect, _, law = head.partition("__")
    return f"{effect} ({law}) #{number}" if law else f"{effect} #{number}"


def bench_diagnose(build, dry_run):
    """plsa diagnose's wall and CPU time on three 60 s runs per withheld effect, with and without the reference."""
    data = bench_script(build, "diagnose_cost.py")
    rows = ["| case (withheld effect, law, seed) | wall / CPU, default | without the reference | selected | "
            "held-out gap left / reference's |", "| --- | --- | --- | --- | --- |"]
    walls = {"with_reference": [], "without_reference": []}
    for c in data["cases"]:
        w, wo = c["with_reference"], c["without_reference"]
        walls["with_reference"].append(w["wall_s"])
        walls["without_reference"].append(wo["wall_s"])
        ref = "-" if w["reference_gap_percent"] is None else f"{w['reference_gap_percent']:.1f}%"
        rows.append(f"| {case_name(c['case'])} | {w['wall_s']:.1f} s / {w['cpu_s']:.1f} s | "
                    f"{wo['wall_s']:.1f} s / {wo['cpu_s']:.1f} s | {'+'.join(w['selected']) or 'nothing'} | "
                    f"{w['gap_after_percent']:.1f}% / {ref} |")
    summary = []
    for mode, label in (("with_reference", "default"), ("without_reference", "--no-identified-reference")):
        v = walls[mode]
        met = sum(1 for x in v if x <= 10.0)
        summary.append(f"{label}: median {statistics.median(v):.1f} s, at most {max(v):.1f} s, "
                       f"{met} of {len(v)} within the 10 s target")
    replace_block(os.path.join(HERE, "bench", "README.md"), "bench-diagnose",
                  stamp("bench/diagnose_cost.py") + f" Seeds {data['seed']}-{data['seed'] + len(data['cases']) - 1}, "
                  f"{data['repeats']} diagnosis per case and mode.\n\n" + "\n".join(rows) + "\n\n" +
                  "; ".join(summary) + ".\n", dry_run)


def gbench_row(b):
    """One benchmark's line: its mean time over its calls (a simulator replay's also per internal step)."""
    its = b["iterations"]
    calls = f"{its / 1e6:.1f} million calls" if its >= 100_000 else f"{its} runs"
    step = b.get("per_internal_step")
    per_step = f", {step * 1e9:.0f} ns per internal step" if step else ""
    t = b["real_time"]
    time = f"{t:.0f}" if t >= 10 else f"{t:.3g}"
    return f"- {b['name']}: {time} {b['time_unit']} (mean of {calls}{per_step})"


def bench_gbench(build, dry_run):
    """The Google Benchmark run of the demo model's update (no per-call clock reads) and of simulator replays."""
    text = run([os.path.join(build, "bench", "plsa-bench"), "--benchmark_format=json"])
    data = json.loads(text[text.index("{"):])
    rows = [gbench_row(b) for b in data["benchmarks"]]
    replace_block(os.path.join(HERE, "bench", "README.md"), "bench-gbench",
                  stamp("plsa-bench") + "\n\n" + "\n".join(rows) + "\n", dry_run)


def machine_tail(lat, call):
    """The fixed work whose p50 is nearest the call's: (its length in words, its p99.9 / p50, its p99.9), or None."""
    fixed = [(k, v) for k, v in lat.items() if k.startswith("fixed work of about ")]
    if not fixed:
        return None
    k, v = min(fixed, key=lambda kv: abs(math.log(kv[1]["p50"] / call["p50"])))
    return k[len("fixed work of "):], v["p99_9"] / v["p50"], v["p99_9"], call["p99_9"]


def tail_verdict(ratios, tails, state_ratios):
    """Over 5x: 'not met' unless each such call's own work stays within 5x (the fastest of each state's calls:
    interrupts hit single calls, a costly state every call) and the fixed work of the nearest length has a
    wall-clock tail over 5x too (the machine's own, same run), which the verdict then says."""
    over = [n for n, r in ratios.items() if r > 5.0]
    if all(n in state_ratios and state_ratios[n] <= 5.0 and tails[n] and tails[n][1] > 5.0 for n in over):
        return ("met by the calls' own work; not met in wall-clock time on this machine, whose fixed work "
                "as long has a tail over 5x too")
    return False


def sensitivity_verdict(whole, moving):
    if whole <= 10000:
        return True
    return "met writing the moving rows only" if moving <= 10000 else False


def targets_table(lat, figures):
    """The demo model's figures against the predictor's targets, p50 unless said."""
    def p50(call):
        return lat[f"demo: {call}"]["p50"]

    def ratio(call):
        v = lat[f"demo: {call}"]
        return v["p99_9"] / v["p50"]

    def state_ratio(call):  # None for calls that do not share states (update)
        v = lat[f"demo: {call}"]
        return v["state_p99_9"] / v["state_p50"] if "state_p50" in v else None

    def verdict(ok):
        return ok if isinstance(ok, str) else "met" if ok else "not met"

    calls = {"update": "update", "held 80": "predict 80, input held, moving", "planned 80": "predict 80, planned input",
             "predict 400": "predict 400, input held, moving", "sensitivity": "sensitivity 80 (jacobian to the plan)",
             "after a hold 80": "predict 80, after a 125 s hold", "after a hold 400": "predict 400, after a 125 s hold"}
    zero_fill = "writing that jacobian's entries once (setZero)"
    jac_rows, jac_cols = int(figures["demo: jacobian rows"]), int(figures["demo: jacobian columns"])
    ratios = {name: ratio(call) for name, call in calls.items()}
    state_ratios = {name: state_ratio(call) for name, call in calls.items() if state_ratio(call)}
    tails = {name: machine_tail(lat, lat[f"demo: {call}"]) for name, call in calls.items()}
    held_after = p50(calls["after a hold 80"])
    segments = figures["100 segments: p99.9 share of the 12.5 ms period"]
    seg = lat["100 segments of the demo's model: update + predict 80 per tick"]
    fast = (figures["demo: speed-up over straightforward, planned (p50)"],
            figures["demo: speed-up over straightforward, held (p50)"])
    rows = [
        ("update <= 0.2 us", f"{fmt(p50(calls['update']))}", p50(calls["update"]) <= 200),
        ("predict 80 held <= 1 us", f"{fmt(p50(calls['held 80']))} while the lag moves; {fmt(held_after)} after a hold",
         p50(calls["held 80"]) <= 1000),
        ("predict 80 planned <= 3 us", fmt(p50(calls["planned 80"])), p50(calls["planned 80"]) <= 3000),
        ("predict 400 <= 10 us", f"{fmt(p50(calls['predict 400']))} held", p50(calls["predict 400"]) <= 10000),
        ("p99.9 within 5x of p50 after any history",
         ", ".join(f"{name} {r:.1f}x" + (f" (fixed work of {tails[name][0]}: {tails[name][1]:.1f}x)" if r > 5 and
                                          tails[name] else "") for name, r in ratios.items()) +
         "; the fastest of each state's calls (the call's own work): " +
         ", ".join(f"{name} {r:.1f}x" for name, r in state_ratios.items()),
         max(ratios.values()) <= 5.0 or tail_verdict(ratios, tails, state_ratios)),
        ("no subnormal state after a 125 s hold", f"{figures['demo: subnormal states after a 125 s hold']:.0f} states",
         figures["demo: subnormal states after a 125 s hold"] == 0),
        (">= 20x a straightforward implementation", f"{fast[0]:.0f}x planned, {fast[1]:.0f}x held", min(fast) >= 20),
        ("100 segments within 10% of a period (tight loop, p99.9)",
         f"{fmt(seg['p50'])} p50, {fmt(seg['p99_9'])} p99.9 ({100 * segments:.1f}%)", segments <= 0.10),
        ("sensitivity 80 x 3 <= 10 us",
         f"{fmt(p50(calls['sensitivity']))} writing every entry; {fmt(p50('sensitivity 80, moving rows only'))} "
         "writing only the rows each plan step moves (JacobianFill::kMovingRows); for scale, writing the "
         f"Jacobian's {jac_rows} x {jac_cols} entries ({jac_rows * jac_cols * 8 // 1000} KB) once takes "
         f"{fmt(p50(zero_fill))} (setZero), and the planned "
         f"prediction it starts from {fmt(p50(calls['planned 80']))}",
         sensitivity_verdict(p50(calls["sensitivity"]), p50("sensitivity 80, moving rows only"))),
    ]
    out = ["| target | measured (p50 unless said) | verdict |", "| --- | --- | --- |"]
    out += [f"| {t} | {m} | {verdict(ok)} |" for t, m, ok in rows]
    return "\n".join(out)
