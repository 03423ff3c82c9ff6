"""PNG plots of a simulation: time histories as in the paper's Figs. 8-13 and the configuration at
each impact as in Fig. 14 (planar) and Fig. 24 (3D).  Needs matplotlib (`pip install -e .[plot]`).

A run that leaves its plane (some point's X3 changes) gets its X3 histories too.  Plots stay readable for
long chains and long runs: beyond LEGEND_MAX curves the curves are coloured by their index with a colour bar
instead of a legend, and the impact configurations are coloured by time with a colour bar."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .model import CompiledModel
from .simulate import SimulationResult

LEGEND_MAX = 10        # curves named in a legend (the colour cycle's length); more: coloured by index, a colour bar
FAINT_IMPACTS = 20     # beyond this many impacts their configurations are drawn thinner and translucent


def _pyplot():
    try:
        import matplotlib
    except ModuleNotFoundError:
        raise RuntimeError("--plot needs matplotlib: pip install 'gibbs-appell-chains[plot]' "
                           "(or pip install matplotlib)") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def point_histories(model: CompiledModel, result: SimulationResult) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities of O_1..O_{n+1} at every sample: arrays (samples, n+1, 3)."""
    reduce = model.layout.reduce
    positions = np.array([model.contact_points(reduce(q)) for q in result.q])
    velocities = np.array([model.contact_velocities(reduce(q), reduce(qd)) for q, qd in zip(result.q, result.qd)])
    return positions, velocities


def _mark_impacts(ax, result: SimulationResult) -> None:
    faint = len(result.impacts) > FAINT_IMPACTS
    for impact in result.impacts:
        ax.axvline(impact.t, color="0.7", lw=0.4 if faint else 0.6, ls="--", zorder=0, alpha=0.5 if faint else 1.0)


def _draw_curves(plt, fig, ax, t, curves, index_label: str) -> None:
    """The curves with a legend, or, beyond LEGEND_MAX of them, coloured by index with a colour bar."""
    if len(curves) <= LEGEND_MAX:
        for values, label, _ in curves:
            ax.plot(t, values, lw=1.0, label=label)
        ax.legend(fontsize=7, ncol=2)
        return
    indices = [index for _, _, index in curves]
    norm = plt.Normalize(min(indices), max(indices))
    for values, _, index in curves:
        ax.plot(t, values, lw=0.6, color=plt.cm.viridis(norm(index)))
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=plt.cm.viridis), ax=ax, label=index_label)


def plot_histories(model: CompiledModel, result: SimulationResult, out_dir: Path) -> list[Path]:
    plt = _pyplot()
    positions, velocities = point_histories(model, result)
    n = model.n
    paths = []
    figures = [("angles", "joint angles (rad)", "k (the curve of θk)",
                [(result.q[:, k + 1], f"θ{k}", k) for k in range(-1, n + 1)])]
    axes = (0, 1) if _is_planar(positions) else (0, 1, 2)
    for axis in axes:
        figures.append((f"positions_X{axis + 1}", f"joint positions along X{axis + 1} (m)", "i (the curve of Oi)",
                        [(positions[:, i, axis], f"O{i + 1}", i + 1) for i in range(n + 1)]))
        figures.append((f"velocities_X{axis + 1}", f"joint velocities along X{axis + 1} (m/s)", "i (the curve of Oi)",
                        [(velocities[:, i, axis], f"O{i + 1}", i + 1) for i in range(n + 1)]))
    for name, ylabel, index_label, curves in figures:
        fig, ax = plt.subplots(figsize=(7, 4))
        _draw_curves(plt, fig, ax, result.t, curves, index_label)
        _mark_impacts(ax, result)
        ax.set_xlabel("t (s)")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{model.scene.name}: {ylabel} (dashed: impacts)")
        fig.tight_layout()
        path = out_dir / f"{model.scene.name}_{name}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)
    return paths


def _is_planar(positions: np.ndarray) -> bool:
    return bool(np.ptp(positions[..., 2]) < 1e-9)


def plot_impact_configurations(model: CompiledModel, result: SimulationResult, out_dir: Path) -> Path:
    """The chain at the start (dashed) and at each impact, coloured by the impact's time (a colour bar, not a
    legend entry per impact), with the touching points as red stars."""
    plt = _pyplot()
    start = model.contact_points(model.q0)
    shapes = [model.contact_points(model.layout.reduce(i.q)) for i in result.impacts]
    times = np.array([i.t for i in result.impacts])
    walls = {w.name: w.position for w in model.scene.walls}
    planar = _is_planar(np.array([start] + shapes))
    fig = plt.figure(figsize=(8, 6))
    ax = fig.add_subplot(111) if planar else fig.add_subplot(111, projection="3d")

    def draw(points, *style, **options):
        if planar:
            return ax.plot(points[:, 0], points[:, 1], *style, **options)
        return ax.plot(points[:, 0], points[:, 2], points[:, 1], *style, **options)

    draw(start, "--o", color="0.35", ms=3, lw=1.0, label="start (t = 0)")
    norm = plt.Normalize(0.0, max(float(result.t_final), float(times.max()) if len(times) else 0.0, 1e-12))
    faint = len(shapes) > FAINT_IMPACTS
    for shape, t in zip(shapes, times):
        draw(shape, "-o", color=plt.cm.viridis(norm(t)), ms=2 if faint else 3, lw=0.7 if faint else 1.2,
             alpha=0.6 if faint else 1.0)
    stars = [shape[c.point - 1] for shape, impact in zip(shapes, result.impacts)
             for c in impact.contacts if c.kind == "wall"]
    if stars:
        draw(np.array(stars), "r*", ms=5 if faint else 8, ls="none", label="touching points")
    from .animate import draw_box
    draw_box(ax, model.scene, planar)
    if not planar:
        for axis, setter in ((0, ax.set_xlim), (2, ax.set_ylim), (1, ax.set_zlim)):
            lo, hi = walls.get(f"x{axis + 1}_min"), walls.get(f"x{axis + 1}_max")
            if lo is not None and hi is not None:
                setter(lo, hi)
    colours = plt.cm.ScalarMappable(norm=norm, cmap=plt.cm.viridis)
    if planar:             # a bar as tall as the box (the axes keep X1 and X2 to scale)
        from mpl_toolkits.axes_grid1 import make_axes_locatable
        fig.colorbar(colours, cax=make_axes_locatable(ax).append_axes("right", size="3%", pad=0.15),
                     label="time of the impact (s)")
    else:
        fig.colorbar(colours, ax=ax, label="time of the impact (s)", shrink=0.7, pad=0.1)
    ax.set_title(f"{model.scene.name}: configuration at each of {len(shapes)} impacts")
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    path = out_dir / f"{model.scene.name}_impacts.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_all(model: CompiledModel, result: SimulationResult, out_dir: str | Path) -> list[Path]:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return plot_histories(model, result, out) + [plot_impact_configurations(model, result, out)]
