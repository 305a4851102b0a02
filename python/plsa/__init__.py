"""plsa: identification and prediction of pneumatic soft actuators (DIO-PWL-OBF).

    import plsa
    plsa.simulate("grid2", "train.csv")
    model = plsa.identify(["train.csv"], scheduling="input")
    plsa.validate(model, "val.csv", horizons=[40, 80])
    data = plsa.read_log("val.csv")              # {column: numpy array}
    p = plsa.Predictor(model)
    p.update(t, u, y); p.predict(80)            # the next 80 samples, input held
    p.install(plsa.Model.load("model-v2.json"))  # adopted at the next update
    plsa.diagnose("sim.json", ["run1.csv", "run2.csv"], out="diag")   # what diagnosis.json holds

Errors in the inputs raise ValueError with the library's message.
"""
import sys as _sys

__version__ = "@PROJECT_VERSION@"

# What the compiled _plsa was built for, filled in by CMake (configure_file).
_BUILT_PYTHON = "@Python3_EXECUTABLE@"
_BUILT_VERSION = (@Python3_VERSION_MAJOR@, @Python3_VERSION_MINOR@)
_PYBIND11_VERSION = tuple(int(p) for p in "@pybind11_VERSION@".split(".")[:2])


def _refuse_another_runtime():
    """An ImportError that says which Python to use, instead of a crash later."""
    here = f"{_sys.executable} (Python {_sys.version_info[0]}.{_sys.version_info[1]})"
    if tuple(_sys.version_info[:2]) != _BUILT_VERSION:
        raise ImportError(
            f"plsa: this module was built for Python {_BUILT_VERSION[0]}.{_BUILT_VERSION[1]} ({_BUILT_PYTHON}), "
            f"not {here}; run it with {_BUILT_PYTHON}, or rebuild with -DPython3_EXECUTABLE={_sys.executable}")
    try:
        import numpy
    except ImportError as e:
        raise ImportError(f"plsa: needs numpy, which {here} cannot import ({e})") from e
    major = int(numpy.__version__.split(".")[0])
    # pybind11 reads numpy's C API table at run time; before 2.12 it knows only numpy 1's.
    if major >= 2 and _PYBIND11_VERSION < (2, 12):
        raise ImportError(
            f"plsa: this module was built with pybind11 {'.'.join(map(str, _PYBIND11_VERSION))}, which cannot use "
            f"numpy {numpy.__version__} (numpy 2 needs pybind11 2.12 or later), the numpy of {here}; run it with "
            f"{_BUILT_PYTHON} and its numpy 1, or rebuild against a newer pybind11")


_refuse_another_runtime()

from ._plsa import Model, Predictor, diagnose, identify, read_log, simulate, validate  # noqa: E402

__all__ = ["__version__", "Model", "Predictor", "diagnose", "identify", "read_log", "simulate", "validate"]
