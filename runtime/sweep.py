"""python -m runtime sweep: a grid or random sample over parameters and start coordinates, run in parallel.

    python -m runtime sweep --scene paper-case1 --vary e_x2_min=0.05:1:20 --vary q.theta_2=-0.1:0.1:10 --out DIR

``--vary NAME=LO:HI:N`` varies a parameter (a name of the model's parameter vector, e.g. e_x2_min) or a start
coordinate (q.NAME, qd.NAME with the names of Eq. 13: theta_-1, theta_0, theta_1..theta_n, X1, X2, X3) over N
values from LO to HI.  Several --vary make a grid (every combination), or, with --samples N, N random points
drawn uniformly in the box (--seed).  Writes DIR/runs.csv (one row per run), DIR/runs.npz (the columns and
the final states) and DIR/sweep.png (a heat map of the impact count and final energy over two varied
quantities, or curves over one).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from codegen.scene import coordinate_names


@dataclass(frozen=True)
class Vary:
    name: str            # 'e_x2_min', 'q.theta_2', 'qd.X1'
    low: float
    high: float
    count: int

    def values(self) -> np.ndarray:
        return np.linspace(self.low, self.high, self.count)


def parse_vary(text: str) -> Vary:
    """'NAME=LO:HI:N' -> Vary, or ValueError naming what is wrong."""
    name, sep, spec = text.partition("=")
    parts = spec.split(":")
    if not sep or not name or len(parts) != 3:
        raise ValueError(f"--vary: expected NAME=LO:HI:N (e.g. e_x2_min=0.05:1:20), got {text!r}")
    try:
        low, high = float(parts[0]), float(parts[1])
        count = int(parts[2])
    except ValueError:
        raise ValueError(f"--vary {name}: LO and HI must be numbers and N an integer, got {spec!r}") from None
    if not (math.isfinite(low) and math.isfinite(high)):
        raise ValueError(f"--vary {name}: LO and HI must be finite, got {spec!r}")
    if count < 1 or count > 1_000_000:
        raise ValueError(f"--vary {name}: N must be in 1..1000000, got {count}")
    return Vary(name, low, high, count)


def check_names(varies: list[Vary], parameter_names: list[str], n: int) -> None:
    coordinates = coordinate_names(n)
    seen = set()
    for vary in varies:
        if vary.name in seen:
            raise ValueError(f"--vary {vary.name}: given twice")
        seen.add(vary.name)
        prefix, _, rest = vary.name.partition(".")
        if prefix in ("q", "qd") and rest:
            if rest not in coordinates:
                raise ValueError(f"--vary {vary.name}: no coordinate {rest!r}; allowed: {', '.join(coordinates)}")
        elif vary.name not in parameter_names:
            raise ValueError(f"--vary {vary.name}: not a parameter of this model ({', '.join(parameter_names)}) "
                             "nor q.NAME / qd.NAME")


def build_runs(varies: list[Vary], samples: int | None = None, seed: int = 0) -> list[dict]:
    """The runs of a sweep: the grid of every combination, or ``samples`` uniform random points."""
    if samples:
        rng = np.random.default_rng(seed)
        points = [[rng.uniform(v.low, v.high) for v in varies] for _ in range(samples)]
    else:
        points = itertools.product(*(v.values() for v in varies))
    runs = []
    for point in points:
        run: dict = {}
        for vary, value in zip(varies, point):
            prefix, _, rest = vary.name.partition(".")
            if prefix in ("q", "qd") and rest:
                run.setdefault(f"{prefix}0", {})[rest] = float(value)
            else:
                run.setdefault("p", {})[vary.name] = float(value)
        runs.append(run)
    return runs


def column_of(vary: Vary) -> str:
    """The ensemble's column for a varied quantity."""
    return vary.name if "." in vary.name else f"p.{vary.name}"


def plot_sweep(study, varies: list[Vary], path) -> None:
    """Impact count and final energy over the varied quantities: heat maps over the first two (grid) or
    scatter (random samples), curves over one."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    impacts, energy = study.column("n_impacts").astype(float), study.column("energy_final")
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    x = study.column(column_of(varies[0])).astype(float)
    if len(varies) == 1:
        for ax, y, label in zip(axes, (impacts, energy), ("impacts", "final energy (J)")):
            ax.plot(x, y, "o-", ms=3)
            ax.set_xlabel(varies[0].name)
            ax.set_ylabel(label)
    else:
        y = study.column(column_of(varies[1])).astype(float)
        for ax, z, label in zip(axes, (impacts, energy), ("impacts", "final energy (J)")):
            grid = len(varies) == 2 and len(x) == varies[0].count * varies[1].count
            if grid:
                shape = (varies[0].count, varies[1].count)
                mesh = ax.pcolormesh(y.reshape(shape), x.reshape(shape), z.reshape(shape), shading="nearest")
            else:
                mesh = ax.scatter(y, x, c=z, s=12)
            fig.colorbar(mesh, ax=ax, label=label)
            ax.set_xlabel(varies[1].name)
            ax.set_ylabel(varies[0].name)
    failed = int(np.sum(study.column("status") != 0))
    fig.suptitle(f"{len(study.rows)} runs" + (f", {failed} stopped early (see runs.csv)" if failed else ""))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
