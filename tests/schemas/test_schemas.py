"""The JSON Schemas in schemas/ against the files plsa writes.

Each file is made by the command-line tool (PLSA_CLI, default
build/apps/plsa beside this repository's sources) in a temporary folder and
validated; checked-in examples are validated as they are. Each schema must
also refuse broken variants of a valid file (a missing required key, a
wrong enum value, an unknown key...), and for the files plsa reads, the
reader must refuse the same variants, so that schema and reader agree.
plsa-bench's --json is checked when PLSA_BENCH names the benchmark binary.

Needs python3-jsonschema and python3-pytest; no Python module build.
"""
import copy
import json
import os
import pathlib
import subprocess

import pytest

jsonschema = pytest.importorskip("jsonschema")

REPO = pathlib.Path(__file__).resolve().parents[2]
SCHEMAS = REPO / "schemas"
CORPUS = REPO / "tests" / "fuzz" / "corpus"


def _tool(env, default):
    path = os.environ.get(env)
    if path:
        assert os.access(path, os.X_OK), f"{env}={path} is not an executable"
        return path
    path = REPO / default
    return str(path) if os.access(path, os.X_OK) else None


CLI = _tool("PLSA_CLI", "build/apps/plsa")
BENCH = os.environ.get("PLSA_BENCH")
needs_cli = pytest.mark.skipif(CLI is None, reason="no plsa CLI (set PLSA_CLI)")


def validator(name):
    schema = json.loads((SCHEMAS / f"{name}.schema.json").read_text())
    return jsonschema.Draft202012Validator(schema)


def errors(name, doc):
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in validator(name).iter_errors(doc)]


def assert_valid(name, doc, what):
    problems = errors(name, doc)
    assert not problems, f"{what} does not match {name}.schema.json:\n  " + "\n  ".join(problems[:10])


def assert_refused(name, doc, why):
    assert errors(name, doc), f"{name}.schema.json accepts a file with {why}"


def load(path):
    return json.loads(pathlib.Path(path).read_text())


def run(*args, ok=True, timeout=120):
    r = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=timeout)
    if ok:
        assert r.returncode == 0, f"plsa {' '.join(map(str, args))} failed ({r.returncode}):\n{r.stderr[-2000:]}"
    return r


# --- broken variants -------------------------------------------------------

def without(*path):
    def f(doc):
        *parent, key = path
        for p in parent:
            doc = doc[p]
        del doc[key]
    return f


def setting(value, *path):
    def f(doc):
        *parent, key = path
        for p in parent:
            doc = doc[p]
        doc[key] = value
    return f


def broken(doc, mutate):
    d = copy.deepcopy(doc)
    mutate(d)
    return d


# --- the files, made once --------------------------------------------------

@pytest.fixture(scope="module")
def out(tmp_path_factory):
    return tmp_path_factory.mktemp("plsa-schemas")


@pytest.fixture(scope="module")
def demo(out):
    d = out / "demo"
    run("demo", "--out", d)
    return d


@pytest.fixture(scope="module")
def sim_config(out):
    p = out / "sim.json"
    run("sim-config", "--out", p)
    return p


@pytest.fixture(scope="module")
def diagnosis(out, sim_config):
    """plsa diagnose on a short simulated run, one candidate, few evaluations (a few seconds)."""
    config = load(sim_config)
    config["creep"]["enabled"] = False  # the candidate
    sim = out / "diagnose-sim.json"
    sim.write_text(json.dumps(config))
    real = out / "real.csv"
    run("simulate", "--experiment", "grid2", "--duration", "40", "--out", real)
    d = out / "diagnosis"
    run("diagnose", "--sim", sim, "--real", real, "--out", d, "--candidates", "creep", "--evaluations", "20",
        "--evaluations-per-parameter", "0", "--threads", "1")
    return d


# --- every schema ----------------------------------------------------------

ALL = sorted(p.name[: -len(".schema.json")] for p in SCHEMAS.glob("*.schema.json"))
CHECKED = {"model", "sim-config", "signal-map", "diagnosis", "diagnose-selfcheck", "demo-fits", "validate-fits",
           "crossval-fits", "generalise", "bench"}


def test_every_schema_is_checked_here():
    assert set(ALL) == CHECKED, "a schema without a test, or a test without its schema"


@pytest.mark.parametrize("name", ALL)
def test_schema_is_valid_draft_2020_12(name):
    schema = load(SCHEMAS / f"{name}.schema.json")
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["$id"] == f"https://plsa.dev/schemas/{name}.schema.json"
    assert schema.get("description")


# --- model files -----------------------------------------------------------

MODEL_BROKEN = [
    ("no 'regions'", without("regions")),
    ("no 'play_start' in version 2", without("play_start")),
    ("play_start 'sideways'", setting("sideways", "play_start")),
    ("partition.scheduling 'smooth'", setting("smooth", "partition", "scheduling")),
    ("schedule_side 'both'", setting("both", "schedule_side")),
    ("output_frame 'polar'", setting("polar", "output_frame")),
    ("an unknown top-level key", setting(1, "from_the_future")),
    ("an unknown key in a region", setting("x", "regions", 0, "comment")),
    ("version 3", setting(3, "version")),
    ("schema 'plsa.other'", setting("plsa.other", "schema")),
    ("a pole outside the unit circle", setting([1.5, 0.0], "poles", 0, 0, 0)),
    ("a negative play width", setting([-0.1], "input_play", 0)),
    ("sample_time_s 0", setting(0, "sample_time_s")),
    ("input_range [0, \"-inf\"]", setting([0.0, "-inf"], "input_range")),
]


@needs_cli
@pytest.mark.parametrize("file", ["model.json", "baseline_paper.json", "baseline_global_linear.json"])
def test_demo_models(demo, file):
    assert_valid("model", load(demo / file), file)


@needs_cli
@pytest.mark.parametrize("why,mutate", MODEL_BROKEN, ids=[w for w, _ in MODEL_BROKEN])
def test_model_refused_by_schema_and_reader(demo, out, why, mutate):
    doc = broken(load(demo / "model.json"), mutate)
    assert_refused("model", doc, why)
    bad = out / "broken-model.json"
    bad.write_text(json.dumps(doc))
    r = run("validate", "--model", bad, "--log", demo / "validate_joystick.csv", ok=False)
    assert r.returncode == 1 and "error" in r.stderr, f"plsa reads a model file with {why}"


def test_model_version_1():
    """Version 1 files may lack the fields added since; version 2 files may not."""
    v2 = load(CORPUS / "model_file" / "seed-small.json")
    assert_valid("model", v2, "the fuzz seed")
    v1 = copy.deepcopy(v2)
    v1["version"] = 1
    for key in ["play_start", "play_coupling", "play_threshold", "play_softening", "schedule_lag_s", "schedule_side",
                "output_frame"]:
        v1.pop(key, None)
    assert_valid("model", v1, "a version 1 file")
    assert_refused("model", dict(v1, version=2), "version 2 without play_start and the later fields")


def test_model_interpolated_partition_takes_levels():
    doc = load(CORPUS / "model_file" / "seed-small.json")
    doc["partition"]["scheduling"] = "interpolated"
    assert_refused("model", doc, "an interpolated partition with 'breakpoints'")
    doc["partition"]["levels"] = doc["partition"].pop("breakpoints")
    assert not [e for e in errors("model", doc) if "partition" in e], errors("model", doc)


# The fuzz corpus's regressions the schema can see (the rest, duplicate keys,
# 1e400 and deep nesting, are the parser's; the partition's cell count the reader's).
@pytest.mark.parametrize("kind,file", [
    ("model", "model_file/seed-small.json"),
    ("sim-config", "sim_config/seed-default.json"),
    ("signal-map", "signal_map/seed1.json"),
])
def test_fuzz_seeds_valid(kind, file):
    assert_valid(kind, load(CORPUS / file), file)


@pytest.mark.parametrize("kind,file", [
    ("model", "model_file/regression-null-range.json"),
    ("model", "model_file/regression-huge-version.json"),
    ("model", "model_file/regression-huge-samples.json"),
    ("model", "model_file/regression-inf-string-bound.json"),
    ("model", "model_file/regression-unknown-key.json"),
    ("model", "model_file/regression-duplicate-output.json"),
    ("signal-map", "signal_map/regression-huge-float-id.json"),
])
def test_fuzz_regressions_refused(kind, file):
    assert_refused(kind, load(CORPUS / file), file)


# --- simulator configurations ----------------------------------------------

SIM_BROKEN = [
    ("hysteresis.formulation 'bouc_wen'", setting("bouc_wen", "hysteresis", "formulation")),
    ("an unknown section", setting({}, "friction")),
    ("an unknown key in a section", setting(1.0, "geometry", "width_m")),
    ("'enabled' on the sensor (not an effect)", setting(True, "sensor", "enabled")),
    ("sample_rate_hz 0", setting(0.0, "sample_rate_hz")),
    ("creep.fraction 0.9 (above 0.5)", setting(0.9, "creep", "fraction")),
    ("enabled 'yes'", setting("yes", "creep", "enabled")),
    ("two bend directions", setting([0.0, 120.0], "geometry", "bend_direction_deg")),
]


@needs_cli
def test_sim_config_written(sim_config):
    assert_valid("sim-config", load(sim_config), "plsa sim-config's output")


@needs_cli
def test_sim_config_calibrated(diagnosis):
    assert_valid("sim-config", load(diagnosis / "calibrated_sim.json"), "diagnose's calibrated_sim.json")


def test_sim_config_checked_in():
    assert_valid("sim-config", load(REPO / "docs" / "softarm-bruder2021-sim.json"), "docs/softarm-bruder2021-sim.json")
    assert_valid("sim-config", {"creep": {"enabled": False}}, "a partial configuration")


@needs_cli
@pytest.mark.parametrize("why,mutate", SIM_BROKEN, ids=[w for w, _ in SIM_BROKEN])
def test_sim_config_refused_by_schema_and_reader(sim_config, out, why, mutate):
    doc = broken(load(sim_config), mutate)
    assert_refused("sim-config", doc, why)
    bad = out / "broken-sim.json"
    bad.write_text(json.dumps(doc))
    r = run("simulate", "--config", bad, "--experiment", "joystick", "--duration", "1", "--out", out / "x.csv",
            ok=False)
    assert r.returncode == 1 and "error" in r.stderr, f"plsa reads a simulator configuration with {why}"


# --- CAN signal maps -------------------------------------------------------

SIGNAL_MAP_BROKEN = [
    ("no 'profile'", without("profile")),
    ("a message without 'signals'", without("messages", 0, "signals")),
    ("endian 'middle'", setting("middle", "messages", 0, "signals", 0, "endian")),
    ("bits 12", setting(12, "messages", 0, "signals", 0, "bits")),
    ("a 29-bit id", setting(0x1FFFFFFF, "messages", 0, "id")),
    ("dlc 9", setting(9, "messages", 0, "dlc")),
    ("scale 0", setting(0, "messages", 0, "signals", 0, "scale")),
    ("an unknown key", setting("x", "messages", 0, "signals", 0, "comment")),
    ("no signals", setting([], "messages", 0, "signals")),
]


def test_signal_map_default_profile():
    assert_valid("signal-map", load(REPO / "docs" / "can-default-profile.json"), "docs/can-default-profile.json")


@pytest.mark.parametrize("why,mutate", SIGNAL_MAP_BROKEN, ids=[w for w, _ in SIGNAL_MAP_BROKEN])
def test_signal_map_refused(why, mutate):
    assert_refused("signal-map", broken(load(REPO / "docs" / "can-default-profile.json"), mutate), why)


# --- diagnosis -------------------------------------------------------------

@needs_cli
def test_diagnosis(diagnosis):
    doc = load(diagnosis / "diagnosis.json")
    assert_valid("diagnosis", doc, "diagnosis.json")
    assert_refused("diagnosis", broken(doc, without("verdict")), "no 'verdict'")
    assert_refused("diagnosis", broken(doc, setting("sure", "confidence", "level")), "confidence.level 'sure'")
    assert_refused("diagnosis", broken(doc, setting("sideways", "where", "by_region", 0, "direction")),
                   "a place's direction 'sideways'")
    assert_refused("diagnosis", broken(doc, setting("plsa.diagnosis v2", "schema")), "schema 'plsa.diagnosis v2'")
    assert_refused("diagnosis", broken(doc, without("ranking", 0, "calibration")), "a candidate without 'calibration'")


@needs_cli
def test_diagnose_selfcheck(out):
    path = out / "selfcheck.json"
    # One single case and one null case, short runs: a few seconds. It exits 1
    # when the targets are not met (they are not, on so little), after writing.
    r = run("diagnose-selfcheck", "--effects", "creep", "--seeds", "1", "--no-pairs", "--null", "1", "--train-s", "10",
            "--heldout-s", "10", "--evaluations", "20", "--evaluations-per-parameter", "0", "--threads", "1",
            "--out", path, ok=False)
    assert r.returncode in (0, 1) and path.exists(), r.stderr[-2000:]
    doc = load(path)
    assert_valid("diagnose-selfcheck", doc, "diagnose-selfcheck's --out")
    assert_refused("diagnose-selfcheck", broken(doc, without("summary")), "no 'summary'")
    assert_refused("diagnose-selfcheck", broken(doc, setting("mine", "truth")), "truth 'mine'")
    assert doc["excitation"] == "holds and ramps"
    assert_refused("diagnose-selfcheck", broken(doc, setting("stairs", "excitation")), "excitation 'stairs'")
    assert_refused("diagnose-selfcheck", broken(doc, setting(["friction"], "cases", 0, "withheld")),
                   "a withheld effect 'friction'")


# --- fits --------------------------------------------------------------------

@needs_cli
def test_demo_fits(demo):
    doc = load(demo / "fits.json")
    assert_valid("demo-fits", doc, "the demo's fits.json")
    assert_refused("demo-fits", broken(doc, without("models", "arx")), "no ARX entry")
    assert_refused("demo-fits", broken(doc, without("scored_samples")), "no 'scored_samples'")
    assert_refused("demo-fits", broken(doc, setting("other.json", "models", "plsa", "file")), "file 'other.json'")
    output = next(iter(doc["outputs"]))
    assert_refused("demo-fits", broken(doc, without("outputs", output, "std")), "an output without 'std'")


@needs_cli
def test_validate_fits(demo, out):
    path = out / "validate.json"
    run("validate", "--model", demo / "model.json", "--log", demo / "validate_joystick.csv", "--horizons", "1,40",
        "--json", path)
    doc = load(path)
    assert_valid("validate-fits", doc, "plsa validate --json")
    output = next(iter(doc["outputs"]))
    assert {"fit_k1", "fit_k40", "rms_k1", "rms_k40"} <= set(doc["outputs"][output])
    assert_refused("validate-fits", broken(doc, without("simulation_start")), "no 'simulation_start'")
    assert_refused("validate-fits", broken(doc, setting(1.0, "outputs", output, "fit_k_sim")), "a key 'fit_k_sim'")
    assert_refused("validate-fits", broken(doc, without("outputs", output, "rms_sim")), "an output without 'rms_sim'")
    assert doc["simulation_unsettled_starts"] == [], "the demo's run starts at rest"
    # The same run logged from 10 s in, where the actuator moves: its start named.
    lines = (demo / "validate_joystick.csv").read_text().splitlines()
    rows = [l for l in lines if not l.startswith("#")]
    moving = out / "moving.csv"
    moving.write_text("\n".join(rows[:1] + rows[1 + 800 :]) + "\n")
    run("validate", "--model", demo / "model.json", "--log", moving, "--json", out / "moving.json")
    doc = load(out / "moving.json")
    assert_valid("validate-fits", doc, "plsa validate --json on a log not from rest")
    assert doc["simulation_unsettled_starts"], doc
    assert doc["scored_samples"]["settle_s"] == 0
    assert_refused("validate-fits", broken(doc, without("simulation_unsettled_starts", 0, "later_s")),
                   "an unsettled start without 'later_s'")
    later = max(u["later_s"] for u in doc["simulation_unsettled_starts"])
    r = run("validate", "--model", demo / "model.json", "--log", moving, "--json", out / "settled.json",
            "--settle", later)
    said = f"(sim from the model output level, sensor yaw registered on the 5 s after the first {later:g} s"
    assert said in r.stdout, r.stdout
    settled = load(out / "settled.json")
    assert_valid("validate-fits", settled, "plsa validate --settle --json")
    assert settled["scored_samples"]["settle_s"] == later
    assert settled["scored_samples"]["first"] >= round(later * 80)
    for u in doc["simulation_unsettled_starts"]:
        assert settled["outputs"][u["output"]]["rms_sim"] < u["rms_error"]


@needs_cli
def test_crossval_fits(out):
    logs = []
    for seed in (2, 3):
        logs.append(out / f"joystick{seed}.csv")
        run("simulate", "--experiment", "joystick", "--duration", "20", "--seed", seed, "--out", logs[-1])
    path = out / "crossval.json"
    printed = run("crossval", "--log", logs[0], "--log", logs[1], "--json", path).stdout
    doc = load(path)
    assert_valid("crossval-fits", doc, "plsa crossval --json")
    assert set(doc["folds"]) == {"joystick2", "joystick3"}
    # Every peer fitted and scored in the same run, each a model of its own.
    fold = doc["folds"]["joystick2"]
    assert set(fold) - {"output_drift_per_s"} == {"plsa", "paper", "global_linear", "arx", "grid_levels",
                                                    "play_bank"}
    # A joystick run holds no staircase: the quantile grid's level count is recorded (20 s: the automatic 2).
    assert fold["grid_levels"] == 2, fold["grid_levels"]
    assert "joystick2    quantile grid: 2 levels per input\n" in printed, printed  # and the table says it
    # The default bank of plays is scored in every fold, its verdict printed and recorded.
    bank = fold["play_bank"]
    verdict = "kept {0.00,0.07,0.20}" if bank["kept"] else "none kept"
    assert f"joystick2    bank of plays: {verdict} (held-out gain " in printed, printed
    assert bank["kept"] == (bank["gain"] > max(2 * bank["gain_se"], 1.0)), bank
    # --play-bank reaches each fold's identification: none scores no bank.
    plain = out / "crossval_no_bank.json"
    printed = run("crossval", "--log", logs[0], "--log", logs[1], "--play-bank", "none", "--json", plain).stdout
    assert "bank of plays" not in printed, printed
    assert all("play_bank" not in f for f in load(plain)["folds"].values())
    assert_refused("crossval-fits", broken(doc, without("folds", "joystick2", "play_bank", "kept")),
                   "a bank verdict without 'kept'")
    assert_refused("crossval-fits", broken(doc, setting(-0.1, "folds", "joystick2", "play_bank", "gain_se")),
                   "a negative standard error")
    sims = {key: fold[key]["bend_deg"]["fit_sim"] for key in ("plsa", "paper", "global_linear", "arx")}
    assert len(set(sims.values())) == 4, sims
    assert_refused("crossval-fits", broken(doc, without("mean", "arx")), "no mean ARX entry")
    assert_refused("crossval-fits", broken(doc, without("mean", "global_linear")), "no mean global linear entry")
    assert_refused("crossval-fits", broken(doc, without("folds", "joystick3", "paper")), "a fold without the paper's")
    assert_refused("crossval-fits", broken(doc, without("folds", "joystick2", "plsa")), "a fold without the model")
    assert_refused("crossval-fits", broken(doc, setting({}, "folds", "joystick2", "LSTM")), "an unknown model 'LSTM'")


@needs_cli
def test_generalise(out):
    """One case with a sensor bias (its physics carries the offset's direction), one seed."""
    path = out / "generalise.json"
    run("generalise", "--case", "sensor_bias.scale_offset", "--seeds", "1", "--json", path, timeout=240)
    doc = load(path)
    assert_valid("generalise", doc, "plsa generalise --json")
    assert [r["case"] for r in doc["rows"]] == ["sensor_bias.scale_offset"]
    assert "sensor_offset_direction_deg" in doc["rows"][0]["physics"]
    assert_refused("generalise", broken(doc, without("rows", 0, "fits", "arx")), "a row without ARX's fits")
    assert_refused("generalise", broken(doc, without("rows", 0, "fits", "noise_free")),
                   "a row without its noise-free ceiling")
    assert_refused("generalise", broken(doc, without("summary", "plsa", "steer_deg", "sim")), "no simulation summary")
    assert_refused("generalise", broken(doc, setting("fast", "rows", 0, "fits", "plsa", "bend_deg", "40")),
                   "a fit that is not a number")
    assert_refused("generalise", broken(doc, setting({}, "rows", 0, "fits", "LSTM")), "an unknown model 'LSTM'")


# --- plsa-bench --------------------------------------------------------------

@pytest.mark.skipif(not BENCH, reason="set PLSA_BENCH to plsa-bench to check its --json (about 15 s)")
def test_bench(out):
    path = out / "bench.json"
    r = subprocess.run([BENCH, "--loop", "1", "--segments", "1", "--json", str(path)], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    doc = load(path)  # hand-written JSON: parsing it is half the check
    assert_valid("bench", doc, "plsa-bench --json")
    assert doc["latency_ns"] and "loop deadline misses" in doc["figures"]
    assert_refused("bench", broken(doc, without("figures")), "no 'figures'")
    key = next(iter(doc["latency_ns"]))
    assert_refused("bench", broken(doc, without("latency_ns", key, "p99_9")), "a latency without 'p99_9'")
    assert_refused("bench", broken(doc, setting("fast", "figures", "loop deadline misses")), "a figure 'fast'")
