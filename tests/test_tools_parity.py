"""The three front ends of one model give the same run: the Python runtime (runtime.simulate, the C loop through
cffi), the standalone C program of ``python -m codegen --standalone`` (built with its Makefile) and the FMI 2.0
FMU (runtime.fmu, run by FMPy).  All three compile the same generated C and the same library with the same
optimisation (-O2; cffi: -O2 after Python's own -O3, the Makefile: -std=c99 -O2, the FMU: -std=c99 -O2; no -march,
so no fused multiply-adds on x86-64), and all three call NAME_sim_advance with the same options, so a run is the
same to round-off: the same impacts (count, times, contacts by name, impulses), the same changes of the resting
contacts and the same final state.

What each row compares, and to what:

* Python against the standalone program (``NAME_example T_END METHOD --rtol ... --exact``, every number printed
  with %.17g): impact count, contacts of each impact and resting-contact changes (rest, release, stick, slip)
  identical, and the stick and slip counts equal to those changes; impact times, impulses
  and the final t, q, qd to 1e-9 relative (RELATIVE); the step counters (steps, rejected, right-hand sides) equal.
* Python against the FMU in one communication step over [0, t_end] (the same single NAME_sim_advance loop as
  the other two): the impacts and the changes of the resting contacts (rest, release, stick, slip) the FMU logs
  (category logEvents: time to 17 digits, contacts by name) and its ``impacts`` and ``resting_contacts`` outputs
  identical in number and contacts, times and the final q, qd (its outputs) to RELATIVE.
* Python against the FMU on a fine communication grid: each fmi2DoStep ends the integration at a communication
  point, so the adaptive steps differ and the runs agree only to the integration tolerance, amplified by the
  chain's sensitivity over the run: the impacts' contacts in the same order, times and final state within the
  row's ``grid_tol`` (an RK4 row steps at the grid too, so its error is of order dt^4 per unit time).

The FMU exposes only the method, rtol, atol, dt and h_max (gac_fmi2.h); a row that sets an event option
(event_samples, event_tol, contact_tol, rest_height, zeno_impacts) says so in ``fmu``, and its FMU columns are
not run rather than compared against a different run.

Rows: the paper's two case studies, a driven chain folding against its joint stops, a chain thrown onto a rough
floor (resting contact, Coulomb friction), an arm on a fixed base (mounted-arm: the model holds only the joints), a
chain of capsules landing at its radius (capsule-chain) and one whose links 1 and 3 strike each other (capsule-fold:
contacts of two links), an arm held by PD joint springs striking a fixed ball (arm-obstacle), two chains in one box
striking each other (two-chains: variables named with the chain prefix, q.c2.theta_1), a chain tumbling
down a rough incline (incline: gravity_direction tilted), the built-in 12-link chain (rolled forward dynamics)
and three random admissible scenes of the fuzz study (studies/fuzz.py, fixed seeds) written as scene files, and
the gimbal-lock scene, which passes the lock of its base chart on the second chart in all three (the C loop
switches).  The capsule-chain, incline, 12-link and fuzz rows run with -m slow, and so do the FMU columns of the
rows whose FMU path another default test takes (paper-case1-rk4, paper-case2, driven-stops, gimbal-lock,
mounted-arm, capsule-fold, two-chains: the default run keeps the FMU of paper-case1, friction-rest and arm-obstacle;
the gimbal-lock FMU passes its lock in tests/test_sim_charts.py, the two-chains FMU runs as simulate in
tests/test_tools_fmu.py).
"""
from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

from codegen.scene import LineLink, default_scene, load_scene
from runtime import load_model, simulate
from runtime.header import library_constants

ROOT = Path(__file__).resolve().parents[1]
RELATIVE = 1e-9                                     # final states, impact times and impulses (round-off)
FMU_OPTIONS = {"method", "rtol", "atol", "dt", "h_max"}           # what the FMU's solver.* parameters hold
EXAMPLE_FLAGS = {"rtol": "--rtol", "atol": "--atol", "dt": "--dt", "h_max": "--h-max",
                 "event_samples": "--event-samples", "event_tol": "--event-tol", "contact_tol": "--contact-tol",
                 "rest_height": "--rest-height", "zeno_impacts": "--zeno-impacts", "max_steps": "--max-steps"}
METHOD_CODES = {method: library_constants()[f"GAC_METHOD_{method.upper()}"] for method in ("rk4", "dopri5", "dop853")}


@dataclass(frozen=True)
class Row:
    """One scene and one run.  scene: a shipped scene name, "links:N" (the built-in N-link chain) or
    "fuzz:SEED-INDEX-K" (run K of structure INDEX of the fuzz study with seed SEED).  grid_tol: the relative
    tolerance of the fine-grid FMU run; grid_until: where that run's impacts stop being comparable at that
    tolerance (a cascade of near-simultaneous landings, grouped by the contact_tol window differently by step
    sequences that differ at the tolerance); fmu: why the FMU cannot run this row ("" when it can)."""

    id: str
    scene: str
    t_end: float
    options: dict = field(default_factory=dict)
    grid_tol: float = 1e-6
    grid_until: float | None = None  # the fine grid: only the impacts before this time (s), no final state
    fmu: str = ""
    slow: bool = False
    fmu_slow: bool = False           # its FMU columns with -m slow (the FMU's path is another default row's)


ROWS = [
    Row("paper-case1", "paper-case1", 1.5, dict(method="dopri5", rtol=1e-10, atol=1e-12)),
    Row("paper-case1-rk4", "paper-case1", 1.5, dict(method="rk4", dt=2e-4), grid_tol=1e-5, fmu_slow=True),
    Row("paper-case2", "paper-case2", 1.0, dict(method="dop853", rtol=1e-10, atol=1e-12), fmu_slow=True),
    Row("paper-case2-events", "paper-case2", 1.0,
        dict(method="dopri5", rtol=1e-9, atol=1e-11, event_samples=9, event_tol=1e-12, contact_tol=1e-7,
             rest_height=1e-4, zeno_impacts=8, h_max=0.01),
        fmu="the FMU has no event_samples, event_tol, contact_tol, rest_height or zeno_impacts parameter"),
    Row("driven-stops", "driven-fold", 1.5, dict(method="dopri5", rtol=1e-10, atol=1e-12), fmu_slow=True),
    Row("friction-rest", "rough-floor", 2.0, dict(method="dopri5", rtol=1e-9, atol=1e-11), grid_until=0.93),
    # the grid's step ends move the chart switches too, and 18 impacts of a spinning chain amplify the difference
    Row("gimbal-lock", "gimbal-lock", 3.0, dict(method="dopri5", rtol=1e-10, atol=1e-12), grid_tol=1e-4, fmu_slow=True),
    # O3 strikes the floor at 1.354 s while O4 rests there: O4 leaves that impact at zero normal velocity, and whether
    # it stays resting is decided at round-off, so steps ending at the grid's points may release it
    Row("mounted-arm", "mounted-arm", 2.0, dict(method="dopri5", rtol=1e-10, atol=1e-12), grid_until=1.36, fmu_slow=True),
    # from 1.70 s the chain lies in the floor's corner with the right wall: its landings group differently
    Row("capsule-chain", "capsule-chain", 2.0, dict(method="dopri5", rtol=1e-10, atol=1e-12), grid_until=1.70,
        slow=True),                                    # (capsule-fold's row has capsules at a wall in the default run)
    Row("capsule-fold", "capsule-fold", 1.0, dict(method="dopri5", rtol=1e-10, atol=1e-12), fmu_slow=True),
    Row("arm-obstacle", "arm-obstacle", 1.5, dict(method="dopri5", rtol=1e-10, atol=1e-12)),
    Row("two-chains", "two-chains", 1.0, dict(method="dopri5", rtol=1e-10, atol=1e-12), fmu_slow=True),
    # gravity along a tilted direction (gravity_direction): the chain tumbles down a rough incline
    Row("incline", "incline", 2.0, dict(method="dopri5", rtol=1e-10, atol=1e-12), slow=True),
    Row("chain12-rolled", "links:12", 0.6, dict(method="dopri5", rtol=1e-9, atol=1e-11), slow=True),
    Row("fuzz-0-0-1", "fuzz:0-0-1", 2.0, dict(method="dop853", rtol=4.519460342714693e-07,
                                               atol=1.4274655908381933e-07), grid_tol=1e-4, slow=True),
    # at 1.3507 s O1 and O2 land on x1_min 40 us apart, and the grid's step ends change which lands first
    Row("fuzz-0-4-1", "fuzz:0-4-1", 2.0, dict(method="dopri5", rtol=3.049050117668382e-10,
                                               atol=9.462290101851901e-13), grid_tol=1e-5, grid_until=1.35, slow=True),
    Row("fuzz-0-2-2", "fuzz:0-2-2", 2.0, dict(method="rk4", dt=0.000151287440173357), slow=True),
]


def row_params(fmu: bool = False):
    """The rows as parameters, slow ones marked (``fmu``: for the FMU columns, which rows with fmu_slow join)."""
    return [pytest.param(row, id=row.id, marks=[pytest.mark.slow] if row.slow or (fmu and row.fmu_slow) else [])
            for row in ROWS]


# ---------------------------------------------------------------------------------------------------------------
# the scenes
# ---------------------------------------------------------------------------------------------------------------
def fuzz_scene_data(seed: int, index: int, k: int) -> tuple[dict, float, dict]:
    """Run k of structure ``index`` of the fuzz study (seed ``seed``) as scene-file data, with its t_end and
    options: the drawn parameters become the links, walls, restitutions and frictions, the drawn start the
    scene's initial state."""
    from studies.fuzz import random_run, random_structure
    rng = np.random.default_rng([seed, index])
    structure = random_structure(rng, index, 4)
    model = load_model(structure, specialise=False)
    for _ in range(k + 1):
        run = random_run(rng, structure, model)
    p = dict(zip(structure.parameter_names(), run.p.tolist()))
    links, j = [], 1
    for i, link in enumerate(structure.links, start=1):
        values = run.p[j:j + len(link.param_names)].tolist()
        j += len(link.param_names)
        if isinstance(link, LineLink):
            item = {"length": values[0], "mu": values[1], "J": values[2:5]}
        else:
            length, mass, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz = values
            item = {"length": length, "mass": mass, "com": [cx, cy, cz],
                    "inertia": [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]}
        if i > 1:
            item["twist_matrix"] = [list(r) for r in structure.twists[i - 2]]
        links.append(item)
    walls = {w.name: p[f"wall_{w.name}"] for w in structure.walls}
    data = {"name": f"fuzz_{seed}_{index}_{k}", "gravity": run.p[0], "links": links, "walls": walls,
            "restitution": {w: p[f"e_{w}"] for w in walls},
            "friction": {w: p.get(f"friction_{w}", 0.0) for w in walls},
            "initial": {"q": run.q0.tolist(), "qd": run.qd0.tolist()}}
    return data, run.t_end, run.options


def scene_source(row: Row, folder: Path):
    """What each front end is given: (the CLI's arguments, what load_model and build_fmu take)."""
    if row.scene.startswith("links:"):
        n = int(row.scene[6:])
        return ["--links", str(n)], default_scene(n)
    if row.scene.startswith("fuzz:"):
        seed, index, k = map(int, row.scene[5:].split("-"))
        data, t_end, options = fuzz_scene_data(seed, index, k)
        assert (t_end, options) == (row.t_end, row.options), "the fuzz study's draw changed: update the row"
        path = folder / f"{data['name']}.json"
        path.write_text(json.dumps(data))
        return ["--scene", str(path)], path
    return ["--scene", row.scene], row.scene


# ---------------------------------------------------------------------------------------------------------------
# one run per front end, as plain data
# ---------------------------------------------------------------------------------------------------------------
@dataclass
class Run:
    impacts: list          # (t, [contact names], [impulses])
    events: list           # (kind, t, contact name): resting contacts made ('rest'), released, stuck or slipping
    t: float
    q: np.ndarray          # the model's coordinates (NAME.h)
    qd: np.ndarray
    counts: tuple | None = None      # (steps, rejected, rhs)
    resting: int | None = None
    transitions: tuple | None = None  # (points that came to stick, began to slip, tangential impacts, Painleve choices)


def python_run(model, row: Row) -> Run:
    result = simulate(model, row.t_end, **row.options)
    assert result.status == 0, result.message
    layout = model.layout
    return Run([(i.t, [c.label for c in i.contacts], [c.impulse for c in i.contacts]) for i in result.impacts],
               [(e.kind, e.t, e.wall if e.wall.startswith("theta_") else f"O{e.point}/{e.wall}")
                for e in result.contact_events],
               result.t_final, layout.reduce(result.q_final), layout.reduce(result.qd_final),
               (result.n_steps, result.n_rejected, result.n_rhs), len(result.resting_final),
               (result.n_sticks, result.n_slips, result.n_tangential_impacts,
                result.n_painleve_choices))


def example_arguments(row: Row) -> list[str]:
    args = [repr(row.t_end), row.options["method"]]
    for key, value in row.options.items():
        if key != "method":
            args += [EXAMPLE_FLAGS[key], repr(value)]
    return args + ["--exact"]


def parse_exact(text: str) -> Run:
    run = Run([], [], float("nan"), np.array([]), np.array([]))
    for line in text.splitlines():
        word, *rest = line.split()
        if word == "impact":
            run.impacts.append((float(rest[0]), rest[1::2], [float(v) for v in rest[2::2]]))
        elif word in ("rest", "release", "stick", "slip"):
            run.events.append((word, float(rest[0]), rest[1]))
        elif word == "end":
            run.t = float(rest[0])
        elif word == "q":
            run.q = np.array(rest, dtype=float)
        elif word == "qd":
            run.qd = np.array(rest, dtype=float)
        elif word == "counts":
            run.counts = tuple(int(v) for v in rest[:3])
        elif word == "transitions":
            run.transitions = tuple(int(v) for v in rest)
    return run


_PRINTING_LOGGER = []     # keeps the callbacks FMPy's native logger proxy points at after a run alive


def _restore_printing_logger() -> None:
    """FMPy's native logger proxy keeps the last custom logger in a global: once simulate_fmu has returned, that
    callback is freed, and the next FMU instantiated in this process with FMPy's default callbacks would call it
    (a crash).  Point the proxy at a printing logger that lives as long as the process."""
    from ctypes import byref
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, printLogMessage
    from fmpy.logging import addLoggerProxy
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(printLogMessage)
    _PRINTING_LOGGER.append(callbacks)
    addLoggerProxy(byref(callbacks))


def fmu_run(path: Path, row: Row, interval: float) -> Run:
    from fmpy import read_model_description, simulate_fmu
    from fmpy.fmi2 import fmi2OK
    md = read_model_description(str(path))
    q_names = [v.name for v in md.modelVariables if v.name.startswith("q.")]
    qd_names = [v.name for v in md.modelVariables if v.name.startswith("qd.")]
    messages = []

    def logger(environment, instance, status, category, message):
        messages.append((status, category.decode(), message.decode()))
    start = {f"solver.{key}": value for key, value in row.options.items() if key in FMU_OPTIONS - {"method"}}
    start["solver.method"] = METHOD_CODES[row.options["method"]]
    try:
        result = simulate_fmu(str(path), stop_time=row.t_end, output_interval=interval, start_values=start,
                              output=[*q_names, *qd_names, "impacts", "resting_contacts", "sticks", "slips",
                                      "tangential_impacts", "painleve_choices"], debug_logging=True,
                              logger=logger)
    finally:
        _restore_printing_logger()
    assert all(status == fmi2OK for status, _, _ in messages), messages
    impacts, events = [], []
    for _, category, message in messages:
        if category != "logEvents":
            continue
        kind, _, rest = message.partition(" at t = ")
        if kind == "impact":
            head, contacts = rest.split(", energy")[0].split(" s: ")
            impacts.append((float(head), contacts.split()[2:], []))
        elif kind in ("rest", "release", "stick", "slip"):
            head, contact = rest.split(" s: ")
            events.append((kind, float(head), contact))
    last = result[-1]
    assert last["impacts"] == len(impacts)
    return Run(impacts, events, float(last["time"]), np.array([last[n] for n in q_names]),
               np.array([last[n] for n in qd_names]), None, int(last["resting_contacts"]),
               tuple(int(last[n]) for n in ("sticks", "slips", "tangential_impacts", "painleve_choices")))


# ---------------------------------------------------------------------------------------------------------------
# comparisons
# ---------------------------------------------------------------------------------------------------------------
def close(a, b, rtol: float, what: str) -> None:
    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    assert a.shape == b.shape, f"{what}: shapes {a.shape} and {b.shape}"
    scale = np.maximum(1.0, np.maximum(np.abs(a), np.abs(b)))
    worst = float(np.max(np.abs(a - b) / scale)) if a.size else 0.0
    assert worst <= rtol, f"{what}: differ by {worst:.3g} (relative, allowed {rtol:g})"


def same_run(python: Run, other: Run, rtol: float, impulses: bool = True) -> None:
    """The same impacts (contacts in the same order, times and impulses to rtol) and final state (to rtol)."""
    assert [c for _, c, _ in other.impacts] == [c for _, c, _ in python.impacts], "the impacts' contacts differ"
    close([t for t, _, _ in other.impacts], [t for t, _, _ in python.impacts], rtol, "impact times")
    if impulses:
        for k, ((_, _, a), (_, _, b)) in enumerate(zip(other.impacts, python.impacts)):
            close(a, b, rtol, f"impulses of impact {k + 1}")
    close(other.t, python.t, rtol, "final t")
    close(other.q, python.q, rtol, "final q")
    close(other.qd, python.qd, rtol, "final qd")


# ---------------------------------------------------------------------------------------------------------------
# the front ends, built once per row
# ---------------------------------------------------------------------------------------------------------------
class FrontEnds:
    """Each row's model, standalone program and FMU, built on first use."""

    def __init__(self, folder: Path):
        self.folder, self.built = folder, {}

    def get(self, row: Row) -> dict:
        if row.scene not in self.built:
            folder = self.folder / row.id
            folder.mkdir()
            cli, source = scene_source(row, folder)
            self.built[row.scene] = {"folder": folder, "cli": cli, "source": source, "model": load_model(source)}
        return self.built[row.scene]

    def python(self, row: Row) -> Run:
        entry = self.get(row)
        key = ("python", row.id)
        if key not in self.built:
            self.built[key] = python_run(entry["model"], row)
        return self.built[key]

    def example(self, row: Row) -> Path:
        entry = self.get(row)
        if "example" not in entry:
            out = entry["folder"] / "standalone"
            subprocess.run([sys.executable, "-m", "codegen", *entry["cli"], "--standalone", "--out", str(out),
                            "--no-compile"], check=True, cwd=ROOT, capture_output=True)
            # -O0: a third of -O2's build, the same arithmetic (IEEE doubles either way; the rough-floor row's output
            # with --exact is byte for byte the same); the -O2 build is run in tests/test_build_standalone.py
            subprocess.run(["make", "-s", "-j2", "CFLAGS=-std=c99 -O0 -Wall -Wextra -pedantic -Werror"], cwd=out,
                           check=True, capture_output=True)
            entry["example"] = out / f"{entry['model'].name}_example"
        return entry["example"]

    def fmu(self, row: Row) -> Path:
        from runtime.fmu import build_fmu
        entry = self.get(row)
        if "fmu" not in entry:
            entry["fmu"] = build_fmu(entry["source"], entry["folder"] / "fmu")
        return entry["fmu"]


@pytest.fixture(scope="module")
def front_ends(tmp_path_factory):
    return FrontEnds(tmp_path_factory.mktemp("parity"))


def needs_fmpy():
    pytest.importorskip("fmpy", reason="FMPy is not installed (pip install -e '.[fmi]'): the FMU column is not run")


# ---------------------------------------------------------------------------------------------------------------
# the tests
# ---------------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("row", row_params())
def test_standalone_program_runs_as_the_python_runtime(row, front_ends):
    python = front_ends.python(row)
    assert python.impacts, "a row must have impacts to compare"
    done = subprocess.run([str(front_ends.example(row)), *example_arguments(row)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    c = parse_exact(done.stdout)
    same_run(python, c, RELATIVE)
    assert [(k, n) for k, _, n in c.events] == [(k, n) for k, _, n in python.events], "resting contacts differ"
    close([t for _, t, _ in c.events], [t for _, t, _ in python.events], RELATIVE, "resting-contact times")
    assert c.counts == python.counts, "the step counters differ"
    assert c.transitions == python.transitions, "the stick, slip, tangential-impact and Painleve-choice counts differ"
    assert c.transitions[:2] == tuple(sum(k == kind for k, _, _ in c.events) for kind in ("stick", "slip")), \
        "the stick and slip counts are not the program's stick and slip records"


@pytest.mark.parametrize("row", row_params(fmu=True))
def test_fmu_in_one_communication_step_runs_as_the_python_runtime(row, front_ends):
    if row.fmu:
        pytest.skip(f"not expressible in the FMU: {row.fmu}")
    needs_fmpy()
    python = front_ends.python(row)
    fmu = fmu_run(front_ends.fmu(row), row, row.t_end)
    same_run(python, fmu, RELATIVE, impulses=False)
    assert fmu.resting == python.resting and fmu.transitions == python.transitions
    assert [(k, n) for k, _, n in fmu.events] == [(k, n) for k, _, n in python.events], "resting contacts differ"
    close([t for _, t, _ in fmu.events], [t for _, t, _ in python.events], RELATIVE, "resting-contact times")


@pytest.mark.parametrize("row", row_params(fmu=True))
def test_fmu_on_a_fine_grid_agrees_to_the_integration_tolerance(row, front_ends):
    if row.fmu:
        pytest.skip(f"not expressible in the FMU: {row.fmu}")
    needs_fmpy()
    python = front_ends.python(row)
    fmu = fmu_run(front_ends.fmu(row), row, row.t_end / 100)
    until = row.t_end if row.grid_until is None else row.grid_until
    a = [(t, sorted(c)) for t, c, _ in python.impacts if t < until]
    b = [(t, sorted(c)) for t, c, _ in fmu.impacts if t < until]
    assert [c for _, c in b] == [c for _, c in a], "the impacts' contacts differ (as sets: found in another order)"
    close([t for t, _ in b], [t for t, _ in a], row.grid_tol, "impact times")
    if row.grid_until is None:
        close(fmu.q, python.q, row.grid_tol, "final q")
        close(fmu.qd, python.qd, row.grid_tol, "final qd")
