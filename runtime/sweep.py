"""python -m runtime sweep: a grid or random sample over parameters and start coordinates, run in parallel.

    python -m runtime sweep --scene paper-case1 --vary e_x2_min=0.05:1:20 --vary q.theta_2=-0.1:0.1:10 --out DIR

``--vary NAME=LO:HI:N`` varies a parameter (a name of the model's parameter vector, e.g. e_x2_min) or a start
coordinate (q.NAME, qd.NAME with the names of Eq. 13: theta_-1, theta_0, theta_1..theta_n, X1, X2, X3) over N
values from LO to HI.  Several --vary (at most MAX_VARIES) make a grid (every combination), or, with --samples N,
N random points drawn uniformly in the box (--seed).  Writes DIR/runs.csv (one row per run), DIR/runs.npz (the
columns and the final states) and DIR/sweep.png: the impact count and final energy as curves over one varied
quantity, heat maps over two (scatter plots for random samples), and over three or more one such panel for each
value of the others (each bin of their ranges for random samples), at most MAX_PANELS of them.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from codegen.scene import coordinate_names

MAX_PANELS = 16      # panels per quantity in sweep.png; beyond them the panels take evenly spaced values
MAX_VARIES = 6       # varied quantities of one sweep: two on each panel's axes, up to four across the panels


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
    if len(varies) > MAX_VARIES:
        raise ValueError(f"--vary: at most {MAX_VARIES} varied quantities (sweep.png draws two on each panel's axes "
                         f"and up to four across its panels), got {len(varies)}")
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


def _is_grid(study, varies: list[Vary]) -> bool:
    """Whether the runs are the full grid of the varies (build_runs without samples): every combination once."""
    columns = [study.column(column_of(v)).astype(float) for v in varies]
    return (len(study.rows) == math.prod(v.count for v in varies)
            and all(np.isin(c, v.values()).all() for c, v in zip(columns, varies))
            and len({tuple(point) for point in zip(*columns)}) == len(study.rows))


def _index_of(values: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The index in values (a vary's grid, ascending or descending) of each of points (all among values)."""
    order = np.argsort(values)
    return order[np.searchsorted(values[order], points)]


def _edges(values: np.ndarray) -> np.ndarray:
    """The cell edges of a heat map over a vary's values: midway between neighbours, a value's own band at
    the ends (a single value gets a band of 10 % of its magnitude or of 1)."""
    if len(values) == 1:
        half = 0.05 * max(abs(float(values[0])), 1.0)
        return np.array([values[0] - half, values[0] + half])
    middle = (values[1:] + values[:-1]) / 2
    return np.r_[2 * values[0] - middle[0], middle, 2 * values[-1] - middle[-1]]


def _shrink(counts: list[int], limit: int) -> list[int]:
    """How many values of each panel dimension to draw so that their product stays within limit: the largest
    count is lowered first, one at a time, none below 2 (MAX_VARIES keeps 2 of each within MAX_PANELS)."""
    kept = list(counts)
    while math.prod(kept) > limit and max(kept) > 2:
        kept[kept.index(max(kept))] -= 1
    return kept


def _panels(study, varies: list[Vary], grid: bool):
    """The two quantities on each panel's axes (y, x), and the panels: (title, mask of the runs it holds).
    A grid puts the two varies with the most values on the axes and draws a panel for every combination
    of the others' values (at most MAX_PANELS, evenly spaced values beyond); random samples put the first
    two on the axes and split the others' ranges into bins."""
    if grid:
        order = sorted(range(len(varies)), key=lambda k: -varies[k].count)
        y, x = sorted(order[:2])
    else:
        y, x = 0, 1
    rest = [k for k in range(len(varies)) if k not in (y, x)]
    columns = {k: study.column(column_of(varies[k])).astype(float) for k in rest}
    wanted = [varies[k].count if grid else (4 if len(rest) == 1 else 3) for k in rest]
    kept = _shrink(wanted, MAX_PANELS)
    notes = [f"{c} of the {w} values of {varies[k].name}" for k, c, w in zip(rest, kept, wanted) if grid and c < w]
    choices = []
    for k, count in zip(rest, kept):
        vary = varies[k]
        if grid:
            values = vary.values()[np.unique(np.linspace(0, vary.count - 1, count).round().astype(int))]
            choices.append([(f"{vary.name} = {v:.4g}", columns[k] == v) for v in values])
        else:
            edges = np.linspace(vary.low, vary.high, count + 1)
            choices.append([(f"{vary.name} in [{a:.3g}, {b:.3g}{']' if j == count - 1 else ')'}",
                             (columns[k] >= a) & ((columns[k] < b) | (j == count - 1)))
                            for j, (a, b) in enumerate(zip(edges[:-1], edges[1:]))])
    panels = []
    for combination in itertools.product(*choices):
        mask = np.ones(len(study.rows), dtype=bool)
        for _, part in combination:
            mask &= part
        titles = [title for title, _ in combination]
        lines = [", ".join(titles[:2]), ", ".join(titles[2:])]         # two lines for three or four
        panels.append(("\n".join(line for line in lines if line), mask))
    return y, x, panels or [("", np.ones(len(study.rows), dtype=bool))], notes


def sweep_figure(study, varies: list[Vary]):
    """Impact count and final energy over the varied quantities (a matplotlib Figure): curves over one; heat
    maps over two (a grid) or scatter plots (random samples); over three or more, one such panel for each
    value (grid) or bin (samples) of the others, with a colour scale shared by the panels of a quantity."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    quantities = ((study.column("n_impacts").astype(float), "impacts"),
                  (study.column("energy_final").astype(float), "final energy (J)"))
    failed = int(np.sum(study.column("status") != 0))
    title = f"{len(study.rows)} runs" + (f", {failed} stopped early (see runs.csv)" if failed else "")
    if len(varies) == 1:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
        x = study.column(column_of(varies[0])).astype(float)
        order = np.argsort(x, kind="stable")                  # random samples come unsorted
        for ax, (z, label) in zip(axes, quantities):
            ax.plot(x[order], z[order], "o-", ms=3)
            ax.set_xlabel(varies[0].name)
            ax.set_ylabel(label)
        fig.suptitle(title)
        return fig
    grid = _is_grid(study, varies)
    y, x, panels, notes = _panels(study, varies, grid)
    columns = len(panels) if len(panels) <= 4 else math.ceil(math.sqrt(len(panels)))
    rows = math.ceil(len(panels) / columns)
    stacked = len(panels) > 1                 # the two quantities one above the other, else side by side
    width = 5.5 if not stacked else 2.9 * columns + 1.2
    height = 4.2 if not stacked else 2 * (2.5 * rows + 0.4)
    fig = plt.figure(figsize=(width * (1 if stacked else 2), height), layout="constrained")
    blocks = fig.subfigures(2, 1) if stacked else fig.subfigures(1, 2)
    ys, xs = (study.column(column_of(varies[k])).astype(float) for k in (y, x))
    for block, (z, label) in zip(blocks, quantities):
        finite = z[np.isfinite(z)]
        norm = plt.Normalize(*(finite.min(), finite.max()) if len(finite) else (0.0, 1.0))
        axes = np.atleast_1d(block.subplots(rows, columns, sharex=True, sharey=True, squeeze=False)).ravel()
        for ax, (panel_title, mask) in zip(axes, panels):
            if grid:
                values_y, values_x = varies[y].values(), varies[x].values()
                cells = np.full((len(values_y), len(values_x)), np.nan)
                cells[_index_of(values_y, ys[mask]), _index_of(values_x, xs[mask])] = z[mask]
                ax.pcolormesh(_edges(values_x), _edges(values_y), cells, norm=norm)
            else:
                ax.scatter(xs[mask], ys[mask], c=z[mask], s=12 if len(panels) == 1 else 8, norm=norm)
                ax.set_xlim(varies[x].low, varies[x].high)
                ax.set_ylim(varies[y].low, varies[y].high)
            ax.set_title(panel_title, fontsize=8)
            ax.locator_params(axis="x", nbins=5)
        for ax in axes[len(panels):]:
            ax.set_visible(False)
        for k, ax in enumerate(axes[:len(panels)]):
            if k + columns >= len(panels):            # nothing drawn below it
                ax.set_xlabel(varies[x].name)
                ax.tick_params(labelbottom=True)
            if ax.get_subplotspec().is_first_col():
                ax.set_ylabel(varies[y].name)
        block.colorbar(plt.cm.ScalarMappable(norm=norm), ax=list(axes[:len(panels)]), label=label)
        if stacked:
            block.suptitle(label, fontsize=10)
    if notes:
        title += f"\npanels at {', '.join(notes)} (every run is in runs.csv)"
    fig.suptitle(title)
    return fig


def plot_sweep(study, varies: list[Vary], path) -> None:
    """Write sweep_figure(study, varies) to path (PNG)."""
    import matplotlib.pyplot as plt
    fig = sweep_figure(study, varies)
    fig.savefig(path, dpi=110)
    plt.close(fig)
