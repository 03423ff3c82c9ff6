"""Many runs of one model: sweeps and Monte Carlo studies, on local threads or on a Dask cluster.

    from runtime import load_model
    from runtime.ensemble import simulate_many
    model = load_model("paper-case1")
    runs = [{"p": {"e_x2_min": e}} for e in np.linspace(0.1, 1.0, 50)]
    study = simulate_many(model, runs, t_end=1.5, workers=2)
    study.to_csv("runs.csv")

Each run is a dict overriding any of ``p`` ({name: value}), ``q0`` / ``qd0`` (the full layout of Eq. 13, or
{coordinate name: value} changing some entries of the scene's start), ``u`` (inputs, as simulate() takes
them) and ``t_end``.  Every run goes through ``runtime.simulate.simulate``; the C loop releases the GIL, so
local threads run the compiled part side by side.  Given a Dask ``distributed.Client`` (or a scheduler
address), the runs go to its workers in chunks; a worker loads the compiled model from the shared build
cache once (the model pickles as its scene), and Dask retries the chunks of a worker that is lost.

A run keeps only the count, first time and energy of its impacts (``simulate(keep_impacts=False)``), not their
records; the GIL is released for each flight stretch between two events.
Results come back in the order of ``runs``, the same whatever the number of workers: one row per run
(its overrides, status, message, impacts, energies, counts), plus, if asked, the final states or the
sampled trajectories as arrays.  A run that fails (a bad override, a stop before t_end) is a row with its
status and message, not a failed study.
"""
from __future__ import annotations

import csv
import math
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from codegen.scene import coordinate_names

from .model import CompiledModel, load_model
from .simulate import simulate

KEEP = ("summary", "final", "samples")
RUN_KEYS = ("p", "q0", "qd0", "u", "t_end")
COLUMNS = ("run", "status", "message", "t_final", "n_impacts", "t_first_impact", "energy_initial", "energy_final",
           "loss_impacts", "energy_drift", "n_steps", "n_rhs")


@dataclass
class Ensemble:
    """What simulate_many returns: ``rows`` (one dict per run, in input order: 'run', the overrides as
    'p.NAME', 'q.NAME', 'qd.NAME', 'u', 't_end' columns, then COLUMNS), ``arrays`` ('q_final', 'qd_final'
    (runs x 15 full layout), or 't', 'q', 'qd' (runs x samples x n + 5)), and ``seconds`` (wall time)."""

    rows: list
    arrays: dict = field(default_factory=dict)
    seconds: float = 0.0
    wall_ms: np.ndarray | None = None     # per run (not part of rows: it varies from one execution to the next)

    @property
    def columns(self) -> list[str]:
        names = []
        for row in self.rows:
            names += [k for k in row if k not in names]
        front = [k for k in names if k not in COLUMNS]
        return ["run"] + [k for k in front if k != "run"] + [k for k in COLUMNS if k != "run"]

    def column(self, name: str) -> np.ndarray:
        return np.array([row.get(name, np.nan) for row in self.rows])

    def to_csv(self, path) -> None:
        with open(path, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=self.columns)
            writer.writeheader()
            for row in self.rows:
                writer.writerow({k: _csv_value(v) for k, v in row.items()})

    def to_npz(self, path) -> None:
        """Every numeric column, and the arrays."""
        numeric = {name: self.column(name) for name in self.columns if name != "message"
                   and all(isinstance(r.get(name, 0.0), (int, float, np.integer, np.floating)) for r in self.rows)}
        np.savez(path, **{f"col_{k}": v for k, v in numeric.items()}, **self.arrays,
                 messages=np.array([r["message"] for r in self.rows]))

    def to_parquet(self, path) -> None:
        try:
            import pyarrow
            import pyarrow.parquet
        except ModuleNotFoundError:
            raise RuntimeError("to_parquet: needs pyarrow (pip install pyarrow); to_csv and to_npz need nothing "
                               "more") from None
        table = pyarrow.table({name: [_csv_value(r.get(name)) for r in self.rows] for name in self.columns})
        pyarrow.parquet.write_table(table, path)


def _csv_value(value):
    if isinstance(value, (list, tuple, np.ndarray)):
        return " ".join(repr(float(x)) for x in np.ravel(value))
    return value


# ---------------------------------------------------------------------------------------------------------
# one run
# ---------------------------------------------------------------------------------------------------------
def check_run(model: CompiledModel, run, index: int) -> None:
    """Refuse a run that is not a dict of the known keys (a mistake in the study, not a result)."""
    if not isinstance(run, dict):
        raise ValueError(f"runs[{index}]: expected a dict of overrides ({', '.join(RUN_KEYS)}), got {run!r}")
    unknown = [k for k in run if k not in RUN_KEYS]
    if unknown:
        raise ValueError(f"runs[{index}]: unknown key {unknown[0]!r}; allowed: {', '.join(RUN_KEYS)}")


def _state(model: CompiledModel, given, default, name: str) -> np.ndarray | None:
    """A full-layout start vector from an override: None, a vector, or {coordinate name: value}."""
    if given is None:
        return None
    if isinstance(given, dict):
        names = coordinate_names(model.n)
        full = np.array(default, dtype=float)
        for key, value in given.items():
            if key not in names:
                raise ValueError(f"{name}[{key}]: no such coordinate; allowed: {', '.join(names)}")
            full[names.index(key)] = float(value)
        return full
    return np.asarray(given, dtype=float)


def run_one(model: CompiledModel, run: dict, index: int, t_end: float, keep: str, options: dict):
    """One run as (row, arrays, wall seconds); a failure is a row with status -2 and the error's message."""
    row = {"run": index}
    for key, value in (run.get("p") or {}).items():
        row[f"p.{key}"] = value
    for prefix, key in (("q", "q0"), ("qd", "qd0")):
        if isinstance(run.get(key), dict):
            row.update({f"{prefix}.{k}": v for k, v in run[key].items()})
    if "t_end" in run:
        row["t_end"] = run["t_end"]
    if "u" in run and not callable(run["u"]):
        row["u"] = np.ravel(run["u"]).tolist() if not hasattr(run["u"], "times") else "schedule"
    start = time.perf_counter()
    try:
        q0 = _state(model, run.get("q0"), model.scene.q0, "q0")
        qd0 = _state(model, run.get("qd0"), model.scene.qd0, "qd0")
        u = run.get("u")
        result = simulate(model, run.get("t_end", t_end), p=run.get("p"), q0=q0, qd0=qd0, u=u, keep_impacts=False,
                          **options)
    except (ValueError, RuntimeError) as exc:
        row.update(status=-2, message=f"refused: {exc}", t_final=math.nan, n_impacts=0, t_first_impact=math.nan,
                   energy_initial=math.nan, energy_final=math.nan, loss_impacts=math.nan,
                   energy_drift=math.nan, n_steps=0, n_rhs=0)
        return row, None, time.perf_counter() - start
    row.update(status=result.status, message=result.message, t_final=result.t_final, n_impacts=result.n_impacts,
               t_first_impact=result.t_first_impact,
               energy_initial=result.energy_initial, energy_final=result.energy_final,
               loss_impacts=result.loss_impacts, energy_drift=result.energy_drift,
               n_steps=result.n_steps, n_rhs=result.n_rhs)
    arrays = None
    if keep == "final":
        arrays = (result.q_final, result.qd_final)
    elif keep == "samples":
        arrays = (result.t, result.q, result.qd)
    return row, arrays, time.perf_counter() - start


def run_chunk(model: CompiledModel, chunk: list, t_end: float, keep: str, options: dict) -> list:
    """Runs [(index, run), ...] one after the other (a Dask task): [(row, arrays, seconds), ...]."""
    return [run_one(model, run, index, t_end, keep, options) for index, run in chunk]


# ---------------------------------------------------------------------------------------------------------
# many runs
# ---------------------------------------------------------------------------------------------------------
def simulate_many(model, runs, t_end: float, *, workers: int = 1, processes: bool = False, client=None,
                  keep: str = "summary", chunk_size: int | None = None, progress: bool = False,
                  **options) -> Ensemble:
    """Simulate every run of ``runs`` (dicts of overrides, module docstring) over [0, t_end].

    workers     local threads (>= 1) when no client is given, or processes with processes=True: the C loop
                releases the GIL, but the Python around it (reading and checking each impact) holds it, so
                threads gain little on short runs with many impacts and processes scale (docs/ensembles.md)
    client      a dask.distributed Client, or a scheduler address ('tcp://host:8786'): the runs go to its
                workers in chunks of ``chunk_size`` runs (default: about 4 chunks per worker)
    keep        'summary' (rows only), 'final' (also q_final, qd_final arrays) or 'samples' (also the sampled
                t, q, qd; give t_eval in options so that every run has the same samples)
    progress    show a progress bar (tqdm) on stderr
    options     passed to simulate() for every run (method, rtol, atol, t_eval, max_impacts, ...)
    """
    if not isinstance(model, CompiledModel):
        model = load_model(model)
    if keep not in KEEP:
        raise ValueError(f"keep: must be one of {KEEP}, got {keep!r}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers: must be an integer >= 1, got {workers!r}")
    if keep == "samples" and options.get("t_eval") is None:
        raise ValueError("keep: 'samples' needs t_eval in the options (the same sample times for every run)")
    runs = list(runs)
    for index, run in enumerate(runs):
        check_run(model, run, index)
    options = dict(options)
    if keep != "samples":
        options.setdefault("t_eval", [])      # no samples: with constant inputs a whole run stays in C
    start = time.perf_counter()
    bar = _progress_bar(len(runs), progress)
    if client is not None:
        results = _on_dask(model, runs, t_end, keep, options, client, chunk_size, bar)
    elif workers == 1:
        results = []
        for index, run in enumerate(runs):
            results.append(run_one(model, run, index, t_end, keep, options))
            bar.update(1)
    elif processes:
        size = chunk_size or max(1, math.ceil(len(runs) / (4 * workers)))
        chunks = [list(enumerate(runs))[i:i + size] for i in range(0, len(runs), size)]
        with ProcessPoolExecutor(max_workers=workers) as pool:     # the model pickles as its scene
            futures = [pool.submit(run_chunk, model, chunk, t_end, keep, options) for chunk in chunks]
            for future in futures:
                future.add_done_callback(lambda f: bar.update(len(f.result())))
            results = [item for future in futures for item in future.result()]
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            futures = [pool.submit(run_one, model, run, index, t_end, keep, options) for index, run in enumerate(runs)]
            for future in futures:
                future.add_done_callback(lambda _: bar.update(1))
            results = [future.result() for future in futures]
    bar.close()
    return _collect(model, results, keep, time.perf_counter() - start)


def _on_dask(model, runs, t_end, keep, options, client, chunk_size, bar):
    from distributed import Client, as_completed
    own = None
    if isinstance(client, str):
        client = own = Client(client)
    try:
        nworkers = max(len(client.scheduler_info().get("workers", {})), 1)
        size = chunk_size or max(1, math.ceil(len(runs) / (4 * nworkers)))
        chunks = [list(enumerate(runs))[i:i + size] for i in range(0, len(runs), size)]
        shared = client.scatter(model, broadcast=True)      # pickled as its scene: loaded once per worker
        futures = [client.submit(run_chunk, shared, chunk, t_end, keep, options, retries=2, pure=False)
                   for chunk in chunks]
        done = {}
        for future in as_completed(futures):
            part = future.result()
            done[futures.index(future)] = part
            bar.update(len(part))
        return [item for k in range(len(futures)) for item in done[k]]
    finally:
        if own is not None:
            own.close()


def _collect(model, results, keep, seconds) -> Ensemble:
    rows = [row for row, _, _ in results]
    arrays = {}
    layout = model.layout
    if keep == "final":
        nq_full = layout.nq_full
        q = np.full((len(rows), nq_full), np.nan)
        qd = np.full((len(rows), nq_full), np.nan)
        for k, (_, a, _) in enumerate(results):
            if a is not None:
                q[k], qd[k] = a
        arrays = {"q_final": q, "qd_final": qd}
    elif keep == "samples":
        first = next((a for _, a, _ in results if a is not None), None)
        if first is not None:
            n_t, nq_full = len(first[0]), layout.nq_full
            q = np.full((len(rows), n_t, nq_full), np.nan)
            qd = np.full((len(rows), n_t, nq_full), np.nan)
            for k, (_, a, _) in enumerate(results):
                if a is not None:
                    m = len(a[0])
                    q[k, :m], qd[k, :m] = a[1], a[2]
            arrays = {"t": first[0], "q": q, "qd": qd}
    return Ensemble(rows, arrays, seconds, np.array([s * 1e3 for _, _, s in results]))


class _NoBar:
    def update(self, n):
        pass

    def close(self):
        pass


def _progress_bar(total: int, show: bool):
    if not show:
        return _NoBar()
    from tqdm import tqdm
    return tqdm(total=total, unit="run", smoothing=0.1, mininterval=0.5)
