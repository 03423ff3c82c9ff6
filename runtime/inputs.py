"""Inputs of a driven model at run time: what ``simulate(..., u=...)`` accepts and how it reaches the C loop.

    u = [0.5, -0.2]                                  constant inputs (one per actuated coordinate)
    u = InputSchedule([0, 1, 2], [[0, 0], [1, 0], [1, 1]], mode="hold")    values at breakpoints
    u = lambda t, q, qd: -k * (q[4] - 0.3)           state feedback from Python (q, qd: the full layout of Eq. 13)
    u = Controller(f, jacobian=J)                    state feedback with its Jacobian J(t, q, qd) -> (du/dq, du/dqd),
                                                     which the sensitivities follow (without it they end there)
    u = pd(model, kp=..., kd=..., target=...)        a PD controller on the actuated coordinates, with its Jacobian

Constant inputs are held by the C loop (``NAME_sim_set_input``).  A schedule is given to the C loop as it is
(``NAME_sim_set_schedule``): the loop ends a step at each of its breakpoints, so that every jump of a held schedule (the
zero-order hold of FMI co-simulation) and every kink of a linear one falls on a step boundary, and evaluates it
in C.  A Python function is called back from C at every stage: the most general and the slowest (a Python call
per stage, about 1-2 us each).  A Controller's Jacobian is called back wherever the C loop's sensitivities take the
flight's tangent (simulate(..., sensitivities=[...]); docs/simulation.md, "Inputs from a controller"); its columns of
the full layout are reduced to the model's coordinates (the fixed ones' columns are not used).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MODES = ("hold", "linear")


@dataclass(frozen=True)
class InputSchedule:
    """Inputs given as values at breakpoints: ``values[k]`` (one per input) from ``times[k]`` on, held until the
    next breakpoint (mode 'hold') or interpolated linearly to it (mode 'linear'); ``values[0]`` before ``times[0]`` and
    the last values after the last breakpoint."""

    times: tuple
    values: tuple
    mode: str = "hold"


@dataclass(frozen=True)
class Controller:
    """State feedback u = function(t, q, qd) with its Jacobian: jacobian(t, q, qd) returns (du/dq, du/dqd), each an
    nu x nq_full array (row i: input i in the order of model.input_names; column k: coordinate k of the full layout
    of Eq. 13, as q and qd are given), in the inputs' units (N m or N) per rad or m, and per rad/s or m/s.
    jacobian None: none (the sensitivities end at the controller, as for a plain function)."""

    function: object
    jacobian: object = None


def pd(model, kp, kd, target=0.0) -> Controller:
    """A PD controller on the model's actuated coordinates, with its Jacobian:
        u_i = -kp_i (q_c - target_i) - kd_i qd_c,     c = the coordinate of input i (model.input_names[i]);
    kp (N m/rad or N/m), kd (N m s/rad or N s/m) and target (rad or m): a number for every input, or one per input."""
    nu = model.nu
    if nu == 0:
        raise ValueError("pd: this model has no inputs (name the actuated coordinates with inputs = [...] in the "
                         "scene)")
    gains = {}
    for name, value in (("kp", kp), ("kd", kd), ("target", target)):
        try:
            array = np.broadcast_to(np.asarray(value, dtype=float), (nu,)).copy()
        except (TypeError, ValueError):
            raise ValueError(f"pd.{name}: expected a number or {nu} numbers ({', '.join(model.input_names)}), "
                             f"got {value!r}") from None
        if not np.all(np.isfinite(array)):
            raise ValueError(f"pd.{name}: must be finite, got {array.tolist()}")
        gains[name] = array
    kp, kd, target = gains["kp"], gains["kd"], gains["target"]
    columns = model.scene.input_coordinates()
    rows = np.arange(nu)
    nq_full = model.layout.nq_full
    du_dq, du_dqd = np.zeros((nu, nq_full)), np.zeros((nu, nq_full))
    du_dq[rows, columns] = -kp
    du_dqd[rows, columns] = -kd

    def function(t, q, qd):
        return -kp * (q[columns] - target) - kd * qd[columns]

    def jacobian(t, q, qd):
        return du_dq, du_dqd

    return Controller(function, jacobian)


class InputSource:
    """A checked description of the inputs of one run, for the simulation driver."""

    def __init__(self, kind: str, nu: int, constant=None, times=None, values=None, function=None,
                 layout=None, jacobian=None):
        self.kind = kind                      # 'constant', 'hold', 'linear' or 'function'
        self.nu = nu
        self.constant = constant              # (nu,) for 'constant'
        self.times, self.values = times, values
        self.function, self.layout = function, layout
        self.jacobian = jacobian              # a Controller's Jacobian (t, q, qd) -> (du/dq, du/dqd), or None
        self.error = None                     # an exception the Python function raised, kept for the driver

    def value_at(self, t: float, q_full=None, qd_full=None) -> np.ndarray:
        """The inputs at time t (and, for a function, state (q, qd) in the full layout)."""
        if self.kind == "constant":
            return self.constant.copy()
        if self.kind == "function":
            return _call(self.function, t, q_full, qd_full, self.nu)
        k = int(np.searchsorted(self.times, t, side="right")) - 1
        if k < 0:
            return self.values[0].copy()
        if self.kind == "hold" or k == len(self.times) - 1:
            return self.values[k].copy()
        w = (t - self.times[k]) / (self.times[k + 1] - self.times[k])
        return self.values[k] + w * (self.values[k + 1] - self.values[k])


def _call(function, t, q, qd, nu: int) -> np.ndarray:
    value = np.asarray(function(t, q, qd), dtype=float).reshape(-1)
    if value.shape != (nu,):
        raise ValueError(f"u: the input function returned {value.shape[0]} values at t = {t:.9g} s; this model has "
                         f"{nu} input(s)")
    if not np.all(np.isfinite(value)):
        raise ValueError(f"u: the input function returned a value that is not finite at t = {t:.9g} s: "
                         f"{value.tolist()}")
    return value


def _call_jacobian(jacobian, t, q, qd, nu: int, nq_full: int) -> tuple[np.ndarray, np.ndarray]:
    where = f"u.jacobian: at t = {t:.9g} s"
    value = jacobian(t, q, qd)
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise ValueError(f"{where}: expected a pair (du/dq, du/dqd), got {type(value).__name__}")
    out = []
    for name, part in zip(("du/dq", "du/dqd"), value):
        try:
            array = np.asarray(part, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{where}: {name} is not numeric") from None
        if array.shape == (nq_full,) and nu == 1:
            array = array.reshape(1, nq_full)
        if array.shape != (nu, nq_full):
            raise ValueError(f"{where}: {name} has shape {array.shape}; expected ({nu}, {nq_full}): a row per input, "
                             "a column per coordinate of the full layout (as q and qd)")
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{where}: {name} has a value that is not finite")
        out.append(array)
    return out[0], out[1]


def input_source(model, u) -> InputSource:
    """Check ``u`` against the model's inputs (model.input_names) and describe it."""
    nu = model.nu
    names = ", ".join(model.input_names) or "none"
    if u is None:
        return InputSource("constant", nu, constant=np.zeros(nu))
    if nu == 0:
        raise ValueError("u: this model has no inputs (the scene declares none; name the actuated coordinates "
                         "with inputs = [...] in the scene)")
    if isinstance(u, Controller):
        if not callable(u.function):
            raise ValueError(f"u.function: expected a function u(t, q, qd), got {u.function!r}")
        if u.jacobian is not None and not callable(u.jacobian):
            raise ValueError(f"u.jacobian: expected a function J(t, q, qd) -> (du/dq, du/dqd) or None, "
                             f"got {u.jacobian!r}")
        return InputSource("function", nu, function=u.function, layout=model.layout, jacobian=u.jacobian)
    if callable(u) and not isinstance(u, InputSchedule):
        return InputSource("function", nu, function=u, layout=model.layout)
    if isinstance(u, InputSchedule):
        if u.mode not in MODES:
            raise ValueError(f"u.mode: must be one of {MODES}, got {u.mode!r}")
        try:
            times = np.asarray(u.times, dtype=float).reshape(-1)
            values = np.asarray(u.values, dtype=float)
        except (TypeError, ValueError):
            raise ValueError("u: an InputSchedule needs numeric times and values") from None
        if values.ndim == 1 and nu == 1:
            values = values.reshape(-1, 1)
        if len(times) < 1 or values.shape != (len(times), nu):
            raise ValueError(f"u.values: expected one row of {nu} value(s) ({names}) per time, i.e. shape "
                             f"({len(times)}, {nu}), got {values.shape}")
        if not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
            raise ValueError(f"u.times: must be finite and strictly increasing, got {times.tolist()}")
        if not np.all(np.isfinite(values)):
            raise ValueError("u.values: must be finite")
        return InputSource(u.mode, nu, times=np.ascontiguousarray(times), values=np.ascontiguousarray(values))
    try:
        constant = np.asarray(u, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"u: expected {nu} number(s) ({names}), an InputSchedule or a function "
                         f"u(t, q, qd), got {u!r}") from None
    if constant.shape != (nu,) or not np.all(np.isfinite(constant)):
        raise ValueError(f"u: expected {nu} finite number(s) ({names}), got {np.asarray(u).tolist()}")
    return InputSource("constant", nu, constant=np.ascontiguousarray(constant))


def attach(model, sim, source: InputSource):
    """Give the inputs to an initialised simulation (NAME_sim *); returns what must stay alive during the run."""
    ffi, lib = model.ffi, model.lib
    if source.kind == "constant":
        set_input(model, sim, source.constant)
        return None
    if source.kind in ("hold", "linear"):
        schedule = ffi.new("gac_schedule *")
        keep = (ffi.from_buffer(source.times), ffi.from_buffer(source.values))
        schedule.n, schedule.nu, schedule.linear = len(source.times), source.nu, int(source.kind == "linear")
        schedule.t = ffi.cast("double *", keep[0])
        schedule.u = ffi.cast("double *", keep[1])
        code = model.c.sim_set_schedule(sim, schedule)
        if code != lib.GAC_OK:
            raise ValueError(f"u: {model.error_message(code)}")
        return schedule, keep
    handle = ffi.new_handle(source)
    _python_controller(model)
    model.c.sim_set_controller(sim, model.c.python_controller, handle)
    if source.jacobian is not None:
        _python_controller_jacobian(model)
        code = model.c.sim_set_controller_jacobian(sim, model.c.python_controller_jacobian)
        if code != model.lib.GAC_OK:
            raise ValueError(f"u.jacobian: {model.error_message(code)}")
    return handle


def set_input(model, sim, u: np.ndarray) -> None:
    code = model.c.sim_set_input(sim, model._ptr(np.ascontiguousarray(u, dtype=float)))
    if code != model.lib.GAC_OK:
        raise ValueError(f"u: {model.error_message(code)}")


def _python_controller(model) -> None:
    """Define NAME_python_controller (declared extern "Python" in the model's cffi declarations) once per module:
    it calls the run's Python function with the full-layout state and writes its value; an exception or a bad
    value is kept on the source and NaN written, so the C loop stops with GAC_ERR_BAD_INPUT."""
    ffi, nq = model.ffi, model.nq

    def controller(t, q, qd, u, user):
        source = ffi.from_handle(user)
        out = ffi.cast("double *", u)
        try:
            layout = source.layout
            q_full = layout.expand(np.frombuffer(ffi.buffer(q, 8 * nq), dtype=float))
            qd_full = layout.expand(np.frombuffer(ffi.buffer(qd, 8 * nq), dtype=float), velocity=True)
            value = _call(source.function, float(t), q_full, qd_full, source.nu)
            for i in range(source.nu):
                out[i] = value[i]
        except BaseException as exc:          # noqa: BLE001 - kept and raised again by the driver
            if source.error is None:
                source.error = exc
            for i in range(source.nu):
                out[i] = float("nan")

    model.c.define_callback("python_controller", controller)


def _python_controller_jacobian(model) -> None:
    """Define NAME_python_controller_jacobian once per module: it calls the run's Jacobian with the full-layout state
    and writes its columns of the model's coordinates (du/dq, du/dqd, nu x nq row-major); an exception or a bad value
    is kept on the source and NaN written (the sensitivities end as not finite; the driver raises it)."""
    ffi, nq = model.ffi, model.nq
    free = list(model.layout.free)
    nq_full = model.layout.nq_full

    def jacobian(t, q, qd, du_dq, du_dqd, user):
        source = ffi.from_handle(user)
        out_q = np.frombuffer(ffi.buffer(du_dq, 8 * source.nu * nq), dtype=float)
        out_qd = np.frombuffer(ffi.buffer(du_dqd, 8 * source.nu * nq), dtype=float)
        try:
            layout = source.layout
            q_full = layout.expand(np.frombuffer(ffi.buffer(q, 8 * nq), dtype=float))
            qd_full = layout.expand(np.frombuffer(ffi.buffer(qd, 8 * nq), dtype=float), velocity=True)
            a, b = _call_jacobian(source.jacobian, float(t), q_full, qd_full, source.nu, nq_full)
            out_q[:] = a[:, free].reshape(-1)
            out_qd[:] = b[:, free].reshape(-1)
        except BaseException as exc:          # noqa: BLE001 - kept and raised again by the driver
            if source.error is None:
                source.error = exc
            out_q[:] = np.nan
            out_qd[:] = np.nan

    model.c.define_callback("python_controller_jacobian", jacobian)
