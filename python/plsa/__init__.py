"""plsa: identification and prediction of pneumatic soft actuators (DIO-PWL-OBF).

    import plsa
    plsa.simulate("grid2", "train.csv")
    model = plsa.identify(["train.csv"], scheduling="input")
    plsa.validate(model, "val.csv", horizons=[40, 80])
    data = plsa.read_log("val.csv")              # {column: numpy array}
    p = plsa.Predictor(model)
    p.update(t, u, y); p.predict(80)            # the next 80 samples, input held

Errors in the inputs raise ValueError with the library's message.
"""
from ._plsa import Model, Predictor, identify, read_log, simulate, validate

__all__ = ["Model", "Predictor", "identify", "read_log", "simulate", "validate"]
