"""The Python module end to end on the built-in simulated actuator."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import plsa


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("runs")
    train, val = d / "train.csv", d / "val.csv"
    plsa.simulate("grid2", str(train), seed=1)
    plsa.simulate("joystick", str(val), seed=2, duration_s=40)
    return train, val


@pytest.fixture(scope="module")
def model(runs):
    lines = []
    # The simulated sensor's yaw drifts (0.02 deg/s): asked for, as the demo does.
    m = plsa.identify([str(runs[0])], scheduling="input", output_drift="auto", progress=lines.append)
    assert any("[5/5]" in l for l in lines), "progress lines reach Python"
    return m


def test_identified_model_predicts_the_validation_run(model, runs, tmp_path):
    assert model.inputs == ["p_1", "p_2", "p_3"]
    assert model.outputs == ["bend_deg", "steer_deg"]
    assert model.output_frame == "tip_cartesian"
    fits = plsa.validate(model, str(runs[1]), horizons=[40, 80])
    for name in model.outputs:
        assert fits[name]["fit"][40] > 90.0, fits
        assert fits[name]["fit_sim"] > 80.0, fits
        assert fits[name]["sim_departure"] is None, fits
    path = tmp_path / "model.json"
    model.save(str(path))
    again = plsa.Model.load(str(path))
    a, b = plsa.validate(again, str(runs[1]), horizons=[40]), plsa.validate(model, str(runs[1]), horizons=[40])
    for name in model.outputs:
        assert a[name]["fit"] == b[name]["fit"] and a[name]["fit_sim"] == b[name]["fit_sim"]
        assert np.array_equal(a[name]["predicted"][40], b[name]["predicted"][40], equal_nan=True)


def test_validate_names_a_log_that_does_not_start_at_rest(model, runs, tmp_path):
    """The validation run logged from 10 s in, where the actuator moves: its
    start counts against the simulation; validate names it, and settling
    leaves it out of the scores."""
    lines = runs[1].read_text().splitlines()
    header = [l for l in lines if l.startswith("#")]
    rows = [l for l in lines if not l.startswith("#")]
    moving = tmp_path / "moving.csv"
    moving.write_text("\n".join(header + rows[:1] + rows[1 + 800 :]) + "\n")
    v = plsa.validate(model, str(moving), horizons=[40])
    named = {n: v[n]["unsettled_start"] for n in model.outputs if v[n]["unsettled_start"] is not None}
    assert named, v
    for n, u in named.items():
        assert u["rms_error"] == pytest.approx(v[n]["rms_sim"], rel=1e-12)
        assert u["rms_later"] < 0.8 * u["rms_error"]
        assert 0.0 <= u["straight_share"] <= 1.0
    later = max(u["later_s"] for u in named.values())
    settled = plsa.validate(model, str(moving), horizons=[40], settle_s=later)
    for n in named:
        assert settled[n]["scored_from"] >= round(later * 80)
        assert settled[n]["fit_sim"] > v[n]["fit_sim"] + 5.0, (settled[n]["fit_sim"], v[n]["fit_sim"])
    from_rest = plsa.validate(model, str(runs[1]), horizons=[40])
    assert all(from_rest[n]["unsettled_start"] is None for n in model.outputs)
    with pytest.raises(ValueError, match="settling time"):
        plsa.validate(model, str(moving), horizons=[40], settle_s=-1.0)


def nrmse_fit(y, yhat):
    return 100.0 * (1.0 - np.linalg.norm(y - yhat) / np.linalg.norm(y - y.mean()))


def test_validate_returns_the_arrays_it_scored(model, runs):
    data = plsa.read_log(str(runs[1]))
    v = plsa.validate(model, str(runs[1]), horizons=[40, 80])
    for name in model.outputs:
        o = v[name]
        n = len(data[name])
        np.testing.assert_array_equal(o["measured"], data[name])
        assert o["simulated"].shape == (n,) and set(o["predicted"]) == {40, 80}
        k80 = o["predicted"][80]
        assert np.isnan(k80[:80]).all() and np.isfinite(k80[80:]).all(), "80 steps ahead starts at sample 80"
        s = o["scored_from"]
        assert 80 <= s < n
        # The fits are the NRMSE fits of these arrays over the scored samples.
        for k in (40, 80):
            assert o["fit"][k] == pytest.approx(nrmse_fit(o["measured"][s:], o["predicted"][k][s:]), abs=1e-9)
        assert o["fit_sim"] == pytest.approx(nrmse_fit(o["measured"][s:], o["simulated"][s:]), abs=1e-9)
        # The simulation error kept over k: sum e(t) e(t-k) / sum e(t-k)^2 over the same samples.
        e = o["measured"] - o["simulated"]
        for k in (40, 80):
            now, back = e[s:], e[s - k : len(e) - k]
            both = np.isfinite(now) & np.isfinite(back)  # no simulation before its start
            kept = np.dot(now[both], back[both]) / np.dot(back[both], back[both])
            assert o["sim_error_kept"][k] == pytest.approx(kept, rel=1e-9)


def run_arrays(path):
    """The log's columns, its inputs (p_1..p_3) and outputs (bend, steer) as rows."""
    data = plsa.read_log(str(path))
    u = np.column_stack([data["p_1"], data["p_2"], data["p_3"]])
    y = np.column_stack([data["bend_deg"], data["steer_deg"]])
    return data, u, y


def fed_predictor(model, run, samples):
    """A predictor fed the run's first samples, each accepted."""
    data, u, y = run
    p = plsa.Predictor(model)
    for k in range(samples):
        assert p.update(data["time_s"][k], u[k], y[k]) == "ok"
    return p


def test_predictor_follows_the_run_and_its_sensitivity_matches_differences(model, runs):
    data, u, y = run = run_arrays(runs[1])
    p = fed_predictor(model, run, 800)
    held = p.predict(80)
    assert held.shape == (80, 2) and np.all(np.isfinite(held))
    # 40 steps ahead the held prediction is within a few degrees of the run
    assert abs(held[39, 0] - y[840, 0]) < 5.0
    # The sensitivity is exact where the schedule holds: the grid chambers
    # held long enough for the schedule's lag to settle (coming down, so the
    # play channels sit on their bands' upper edges), the third chamber (no
    # grid node: it acts through the channels' coupling) planned.
    t = data["time_s"][799]
    high, low = np.array([0.33, 0.33, 0.0]), np.array([0.25, 0.25, 0.0])
    for k in range(1900):
        t += model.sample_time_s
        assert p.update(t, high if k < 400 else low, y[799]) == "ok"
    plan = np.tile(low, (79, 1))
    plan[:, 2] = 0.08 + 0.002 * np.arange(79)  # rising: pushes the channels down every step
    jac = p.sensitivity(80, plan)
    assert jac.shape == (160, 237)
    # With its prediction: the same Jacobian and predict()'s prediction, from one call.
    jac_too, predicted = p.sensitivity(80, plan, with_prediction=True)
    assert np.array_equal(jac_too, jac) and np.array_equal(predicted, p.predict(80, plan))
    eps = 1e-6
    for s in (0, 10, 40):
        up, down = plan.copy(), plan.copy()
        up[s, 2] += eps
        down[s, 2] -= eps
        diff = (p.predict(80, up) - p.predict(80, down)) / (2 * eps)
        column = jac[:, s * 3 + 2].reshape(80, 2)
        assert np.abs(diff).max() > 1e-3, "the plan moves nothing: the check shows nothing"
        assert np.allclose(column, diff, atol=1e-5 * np.abs(diff).max() + 1e-7), (s, np.abs(column - diff).max())


def test_levels_set_a_quantile_grid(runs):
    """The joystick run holds no staircase: its grid is a quantile grid of the
    levels asked for (40 s: 2 by default, under 10 s per region of 3)."""
    two = plsa.identify([str(runs[1])], scheduling="input")
    three = plsa.identify([str(runs[1])], scheduling="input", levels=3)
    assert two.regions < three.regions, (two.regions, three.regions)
    with pytest.raises(ValueError, match="quantile levels"):
        plsa.identify([str(runs[1])], levels=-1)


def test_angle_unit_is_read_from_the_data_or_given(runs, tmp_path):
    """Angles logged in radians under names without a unit (theta, phi) are
    read as radians; angle_unit overrides; another unit is refused by name."""
    rows = [line for line in open(runs[1]).read().splitlines() if not line.startswith("#")]
    names = rows[0].split(",")
    data = np.array([[float(v) for v in row.split(",")] for row in rows[1:]])
    for n in ("bend_deg", "steer_deg"):
        data[:, names.index(n)] *= math.pi / 180
    names[names.index("bend_deg")], names[names.index("steer_deg")] = "theta", "phi"
    path = tmp_path / "radians.csv"
    np.savetxt(str(path), data, delimiter=",", header=",".join(names), comments="")
    lines = []
    rad = plsa.identify([str(path)], outputs=["theta", "phi"], scheduling="input", progress=lines.append)
    assert rad.output_frame == "tip_cartesian" and rad.output_unit == "rad", rad
    assert any("angles in rad" in line for line in lines), lines
    given = plsa.identify([str(path)], outputs=["theta", "phi"], scheduling="input", angle_unit="deg")
    assert given.output_unit == "deg"
    with pytest.raises(ValueError, match="deg or rad, got 'grad'"):
        plsa.identify([str(path)], outputs=["theta", "phi"], angle_unit="grad")


def test_bad_input_gets_a_clear_error(model, runs, tmp_path):
    with pytest.raises(ValueError, match="no_such_column"):
        plsa.identify([str(runs[0])], inputs=["no_such_column"])
    with pytest.raises(ValueError, match="scheduling 'sideways'"):
        plsa.identify([str(runs[0])], scheduling="sideways")
    with pytest.raises(ValueError, match="experiment 'staircase9'"):
        plsa.simulate("staircase9", str(tmp_path / "x.csv"))
    p = plsa.Predictor(model, max_horizon=50)
    with pytest.raises(ValueError, match="no sample yet"):
        p.predict(10)
    with pytest.raises(ValueError, match="horizon 80 outside 1..50"):
        p.predict(80)
    with pytest.raises(ValueError, match="3 inputs and 2 outputs"):
        p.update(0.0, np.zeros(2), np.zeros(2))
    assert p.update(0.0, np.array([0.2, 0.2, 0.0]), np.array([1.0, 0.0])) == "ok"
    assert p.update(0.0, np.array([0.2, 0.2, 0.0]), np.array([1.0, 0.0])) == "time did not increase"
    assert p.update(math.nan, np.array([0.2, 0.2, 0.0]), np.array([1.0, 0.0])) == "sample has NaN or Inf"
    with pytest.raises(ValueError, match="buffer of the wrong size"):
        p.predict(10, np.zeros((9, 2)))
    with pytest.raises(ValueError, match="buffer of the wrong size"):
        p.predict(10, np.zeros((51, 3)))
    # A plan in any layout or integer type predicts as the same plan in numpy's default one.
    plan = np.array([[0.25, 0.2, 0.0]] * 9) + 0.01 * np.arange(9)[:, None]
    expected = p.predict(10, plan)
    assert np.array_equal(p.predict(10, np.asfortranarray(plan)), expected)
    assert np.array_equal(p.predict(10, plan[::-1][::-1]), expected)
    assert p.predict(10, np.zeros((9, 3), dtype=np.int64)).shape == (10, 2)
    assert not np.array_equal(p.predict(10, plan[:4]), expected), "a shorter plan holds its last row"
    # A plan is taken as update takes an input (it was predicted without a word).
    with pytest.raises(ValueError, match="predict: input .or a planned one. outside the accepted range"):
        p.predict(10, np.full((9, 3), 50.0))
    # Found by a probe of this module: each was taken without a word, or grew memory without bound.
    with pytest.raises(ValueError, match="duration_s must be a finite number of seconds >= 0"):
        plsa.simulate("joystick", duration_s=-5.0)
    with pytest.raises(ValueError, match="grid2 has its own"):
        plsa.simulate("grid2", duration_s=10.0)
    with pytest.raises(ValueError, match="poles per pair must be 1 to 20"):
        plsa.identify([str(runs[0])], poles=2**31 - 1)
    with pytest.raises(ValueError, match="NUL byte"):
        plsa.read_log(str(runs[0]) + "\0.csv")
    with pytest.raises(ValueError, match="NUL byte"):
        plsa.Model.load(str(tmp_path / "m.json") + "\0x")
    with pytest.raises(ValueError, match="threads must be 1 to 64, got 0"):
        plsa.diagnose(str(tmp_path / "sim.json"), [str(runs[0])], threads=0)
    with pytest.raises(ValueError, match="evaluations must be 20 to 100000, got -1"):
        plsa.diagnose(str(tmp_path / "sim.json"), [str(runs[0])], evaluations=-1)
    long = plsa.Predictor(model, max_horizon=5000)
    long.update(0.0, np.array([0.2, 0.2, 0.0]), np.array([1.0, 0.0]))
    with pytest.raises(ValueError, match="horizon 1001 is over 1000"):
        long.sensitivity(1001, np.zeros((1000, 3)))
    with pytest.raises(ValueError, match="the plan needs at least 9 rows of 3 inputs, got 2 x 3"):
        long.sensitivity(10, np.zeros((2, 3)))
    # A message quoting bytes that are not UTF-8 keeps its text (it arrived empty).
    bad = tmp_path / "bad.csv"
    bad.write_bytes(b"time_s,a\n0,1\n0.1,\xff\xfe\n")
    with pytest.raises(RuntimeError, match=r"bad.csv:3: column 'a': '\\xff\\xfe' is not a number"):
        plsa.read_log(str(bad))


def test_objects_made_without_init_raise_instead_of_crashing(model):
    """Model.__new__(Model) makes an object with no C++ value behind it; any
    use of it (a method, or as an argument) crashed the interpreter."""
    script = """
import plsa, sys
m = plsa.Model.load(sys.argv[1])
uses = [lambda: plsa.Predictor.__new__(plsa.Predictor).update(0.0, [0.0] * 3, [0.0] * 2),
        lambda: plsa.Predictor.__new__(plsa.Predictor).inputs,
        lambda: plsa.Model.__new__(plsa.Model).inputs,
        lambda: repr(plsa.Model.__new__(plsa.Model)),
        lambda: plsa.Predictor(plsa.Model.__new__(plsa.Model)),
        lambda: plsa.Predictor(m).install(plsa.Model.__new__(plsa.Model))]
for use in uses:
    try:
        use()
        print("no error")
    except TypeError as e:
        print("TypeError", e)
print(plsa.Predictor(m).inputs)
"""
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "model.json")
        model.save(path)
        run = subprocess.run([sys.executable, "-c", script, path], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    lines = run.stdout.splitlines()
    assert len(lines) == 7, run.stdout
    for line in lines[:6]:
        assert line.startswith("TypeError this plsa.") and "made by __new__ without __init__" in line, line
    assert lines[6] == "3"


def test_read_log_decodes_a_candump_bus_log(tmp_path):
    # Three cycles of plsa's default CAN profile, as `candump -l` writes them:
    # counter in byte 6, checksum (id low + id high + other bytes) in byte 7.
    def frame(can_id, raw16, counter):
        data = []
        for v in raw16 + [0] * (3 - len(raw16)):
            data += [v & 0xFF, v >> 8]
        data.append(counter)
        data.append((can_id & 0xFF) + (can_id >> 8) + sum(data))
        data[-1] &= 0xFF
        return "%03X#" % can_id + "".join("%02X" % b for b in data)

    lines = []
    for k in range(4):
        t = 1764150000.0 + 0.0125 * k
        lines.append("(%.6f) can0 %s" % (t, frame(0x100, [10000 + k, 20000, 0], k)))
        lines.append("(%.6f) can0 %s" % (t, frame(0x200, [10000 + 1000 * k, 20000, 0], k)))
        lines.append("(%.6f) can0 %s" % (t, frame(0x210, [1000 + k, 65536 - 500], k)))
    path = tmp_path / "candump-2026-11-26_120000.log"
    path.write_text("\n".join(lines) + "\n")
    data = plsa.read_log(str(path))
    assert list(data) == ["time_s", "p_1", "p_2", "p_3", "cmd_1", "cmd_2", "cmd_3", "bend_deg", "steer_deg"]
    assert np.allclose(data["time_s"], [0.0, 0.0125, 0.025, 0.0375], atol=1e-6)
    assert np.allclose(data["p_1"], [0.1, 0.11, 0.12, 0.13], atol=1e-9)
    assert np.allclose(data["steer_deg"], -5.0, atol=1e-9)


def lcm_events(path):
    """(channel, data) of every event of an LCM event log (its documented layout)."""
    import struct
    raw = path.read_bytes()
    at, events = 0, []
    while at < len(raw):
        sync, _, _, channel_len, data_len = struct.unpack(">IqqII", raw[at:at + 28])
        assert sync == 0xEDA1DA01
        channel = raw[at + 28:at + 28 + channel_len].decode()
        data = raw[at + 28 + channel_len:at + 28 + channel_len + data_len]
        events.append((channel, data))
        at += 28 + channel_len + data_len
    return events


def test_the_lcm_types_decode_what_plsa_records(tmp_path):
    import os
    import subprocess
    plsa_lcm = pytest.importorskip("plsa_lcm", reason="a build without LCM has no plsa_lcm")
    if "PLSA_EXE" not in os.environ:
        pytest.skip("PLSA_EXE (the plsa tool, which records LCM event logs) is not set")
    log = tmp_path / "run.lcmlog"
    subprocess.run([os.environ["PLSA_EXE"], "simulate", "--experiment", "joystick", "--duration", "2", "--seed", "2",
                    "--out", str(log)], check=True, capture_output=True)
    states = [plsa_lcm.actuator_state_t.decode(d) for c, d in lcm_events(log) if c == "PLSA_STATE"]
    csv = tmp_path / "run.csv"
    subprocess.run([os.environ["PLSA_EXE"], "convert", "--in", str(log), "--out", str(csv)], check=True,
                   capture_output=True)
    as_csv = plsa.read_log(str(csv))
    assert len(states) == len(as_csv["bend_deg"]) >= 160  # 2 s at 80 Hz at least
    direct = plsa.read_log(str(log))  # the event log itself, as the tools read it
    assert list(direct) == list(as_csv)
    for name in as_csv:
        assert np.allclose(direct[name], as_csv[name], rtol=1e-12, atol=1e-9), name
    assert [s.seq for s in states[:3]] == [states[0].seq, states[0].seq + 1, states[0].seq + 2]
    assert np.allclose([s.bend_deg for s in states], as_csv["bend_deg"])
    assert np.allclose([s.pressure_bar[0] for s in states], as_csv["p_1"])
    # Encoded in Python, decoded the same: the types carry plsa's fields.
    again = plsa_lcm.actuator_state_t.decode(states[5].encode())
    assert again.steer_deg == states[5].steer_deg and again.n_chambers == 3


def test_import_refuses_a_numpy_its_pybind11_cannot_read(tmp_path):
    """A numpy 2 beside a module built with pybind11 < 2.12 is an ImportError naming both, not a crash later."""
    import os
    import subprocess
    import sys

    fake = tmp_path / "numpy"
    fake.mkdir()
    (fake / "__init__.py").write_text('__version__ = "2.0.0"\n')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    r = subprocess.run([sys.executable, "-c", "import plsa"], env=env, capture_output=True, text=True)
    if plsa._PYBIND11_VERSION < (2, 12):
        assert r.returncode != 0
        assert "ImportError" in r.stderr and "numpy 2.0.0" in r.stderr and "pybind11" in r.stderr, r.stderr
        assert sys.executable in r.stderr or plsa._BUILT_PYTHON in r.stderr, r.stderr
    else:
        assert r.returncode == 0, r.stderr


def test_version_is_the_tools():
    import os
    import re
    import subprocess

    assert re.fullmatch(r"\d+\.\d+\.\d+", plsa.__version__), plsa.__version__
    exe = os.environ.get("PLSA_EXE")
    if exe:
        out = subprocess.run([exe, "--version"], capture_output=True, text=True, check=True).stdout
        assert plsa.__version__ in out, out


def test_the_plotting_example_plots_what_validate_scores(model, runs, tmp_path):
    pytest.importorskip("matplotlib", reason="python3-matplotlib is not installed (scripts/plsa-dev test installs it)")
    example = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "validate_and_plot.py")
    model_path, out = tmp_path / "model.json", tmp_path / "plot.png"
    model.save(str(model_path))
    r = subprocess.run([sys.executable, example, str(model_path), str(runs[1]), str(out), "--horizon", "40"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    with open(out, "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    fits = plsa.validate(model, str(runs[1]), horizons=[40])
    for name in model.outputs:
        assert f"{name}: 40-step fit {fits[name]['fit'][40]:.1f}%, simulation {fits[name]['fit_sim']:.1f}%" in r.stdout
    # The plot is never written over an input.
    r = subprocess.run([sys.executable, example, str(model_path), str(runs[1]), str(runs[1])],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "would overwrite an input" in r.stderr


def test_simulate_returns_the_run_it_writes(tmp_path):
    path = tmp_path / "run.csv"
    run = plsa.simulate("joystick", str(path), seed=3, duration_s=5)
    again = plsa.simulate("joystick", seed=3, duration_s=5)  # no path: arrays only
    read = plsa.read_log(str(path))
    assert set(run) == set(read) and {"time_s", "p_1", "bend_deg"} <= set(run)
    for name in read:
        np.testing.assert_array_equal(run[name], again[name])
        np.testing.assert_allclose(run[name], read[name], rtol=1e-15, atol=0)  # the CSV keeps every digit


def test_a_predictor_adopts_an_installed_model_at_its_next_update(model, runs):
    data, u, y = run = run_arrays(runs[1])
    p = fed_predictor(model, run, 200)
    before = p.predict(80)
    assert p.model_id == 0
    p.install(model)  # the same model again, as a re-identification might give
    assert p.model_id == 0, "adopted only at the next update"
    assert p.update(data["time_s"][200], u[200], y[200]) == "ok"
    assert p.model_id == 1
    fresh = fed_predictor(model, run, 201)
    np.testing.assert_allclose(p.predict(80), fresh.predict(80), atol=1e-9)
    assert not np.array_equal(before, p.predict(80)), "the state moved on with the sample"
    # A model of another structure (two inputs, one output) is refused by name.
    small = os.path.join(os.path.dirname(__file__), "..", "..", "tests", "data", "small_model.json")
    with pytest.raises(ValueError, match="structure"):
        p.install(plsa.Model.load(small))
    assert p.update(data["time_s"][201], u[201], y[201]) == "ok" and p.model_id == 1



def test_diagnose_names_the_withheld_effect_and_writes_its_report(tmp_path):
    exe = os.environ.get("PLSA_EXE")
    if not exe:
        pytest.skip("PLSA_EXE is not set (ctest sets it to the built plsa tool, which writes the configurations)")
    import json

    # "Real" runs from an actuator with hysteresis; a simulator without it.
    subprocess.run([exe, "sim-config", "--out", str(tmp_path / "full.json")], check=True, capture_output=True)
    config = json.loads((tmp_path / "full.json").read_text())
    for effect in ("deadzone", "stiffening", "coupling", "pneumatic_lag", "creep", "sensor_bias"):
        config[effect]["enabled"] = False
    (tmp_path / "truth.json").write_text(json.dumps(config))
    config["hysteresis"]["enabled"] = False
    (tmp_path / "sim.json").write_text(json.dumps(config))
    runs = []
    for experiment, seed, extra in (("staircase1", "3", []), ("joystick", "4", ["--duration", "30"])):
        runs.append(str(tmp_path / f"{experiment}.csv"))
        subprocess.run([exe, "simulate", "--config", str(tmp_path / "truth.json"), "--experiment", experiment,
                        "--seed", seed, "--out", runs[-1]] + extra, check=True, capture_output=True)
    lines = []
    d = plsa.diagnose(str(tmp_path / "sim.json"), runs, candidates=["hysteresis", "creep"], evaluations=60,
                      progress=lines.append, out=str(tmp_path / "diag"))
    assert [c["effect"] for c in d["ranking"]][0] == "hysteresis", d["ranking"]
    assert any("nominal calibration" in l for l in lines), lines[:5]
    assert d == json.loads((tmp_path / "diag" / "diagnosis.json").read_text())
    assert (tmp_path / "diag" / "report.html").read_text().startswith("<!DOCTYPE html>")
    # A run named as one of the report's files, in the report's folder, is never written over.
    trace = tmp_path / "trace.csv"
    trace.write_bytes((tmp_path / "joystick.csv").read_bytes())
    with pytest.raises(ValueError, match="would write trace.csv over the input"):
        plsa.diagnose(str(tmp_path / "sim.json"), [runs[0], str(trace)], out=str(tmp_path))
    assert trace.read_bytes() == (tmp_path / "joystick.csv").read_bytes()
    with pytest.raises(ValueError, match="output_map"):
        plsa.diagnose(str(tmp_path / "sim.json"), runs, output_map="polar")
