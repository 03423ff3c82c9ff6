"""PNG plots of a simulation: time histories as in the paper's Figs. 8-13 and the configuration at
each impact as in Fig. 14 (planar) and Fig. 24 (3D).  Needs matplotlib (`pip install -e .[plot]`)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .model import CompiledModel
from .simulate import SimulationResult


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
    for impact in result.impacts:
        ax.axvline(impact.t, color="0.7", lw=0.6, ls="--", zorder=0)


def plot_histories(model: CompiledModel, result: SimulationResult, out_dir: Path) -> list[Path]:
    plt = _pyplot()
    positions, velocities = point_histories(model, result)
    n = model.n
    paths = []
    figures = [("angles", "joint angles (rad)", [(result.q[:, k + 1], f"θ{k}") for k in range(-1, n + 1)])]
    for axis in (0, 1):
        figures.append((f"positions_X{axis + 1}", f"joint positions along X{axis + 1} (m)",
                        [(positions[:, i, axis], f"O{i + 1}") for i in range(n + 1)]))
        figures.append((f"velocities_X{axis + 1}", f"joint velocities along X{axis + 1} (m/s)",
                        [(velocities[:, i, axis], f"O{i + 1}") for i in range(n + 1)]))
    for name, ylabel, curves in figures:
        fig, ax = plt.subplots(figsize=(7, 4))
        for values, label in curves:
            ax.plot(result.t, values, lw=1.0, label=label)
        _mark_impacts(ax, result)
        ax.set_xlabel("t (s)")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{model.scene.name}: {ylabel} (dashed: impacts)")
        ax.legend(fontsize=7, ncol=2)
        fig.tight_layout()
        path = out_dir / f"{model.scene.name}_{name}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)
    return paths


def _is_planar(positions: np.ndarray) -> bool:
    return np.ptp(positions[..., 2]) < 1e-9


def plot_impact_configurations(model: CompiledModel, result: SimulationResult, out_dir: Path) -> Path:
    plt = _pyplot()
    shapes = [model.contact_points(model.q0)] + [model.contact_points(model.layout.reduce(i.q))
                                                 for i in result.impacts]
    labels = ["t = 0"] + [f"#{k} t = {i.t:.4f} s" for k, i in enumerate(result.impacts, start=1)]
    walls = {w.name: w.position for w in model.scene.walls}
    planar = _is_planar(np.array(shapes))
    fig = plt.figure(figsize=(8, 6))
    ax = fig.add_subplot(111) if planar else fig.add_subplot(111, projection="3d")
    colours = plt.cm.viridis(np.linspace(0, 1, len(shapes)))
    for shape, label, colour in zip(shapes, labels, colours):
        if planar:
            ax.plot(shape[:, 0], shape[:, 1], "-o", color=colour, ms=3, lw=1.2, label=label)
        else:
            ax.plot(shape[:, 0], shape[:, 2], shape[:, 1], "-o", color=colour, ms=3, lw=1.2, label=label)
    for k, impact in enumerate(result.impacts, start=1):          # mark the touching points
        shape = shapes[k]
        for c in (c for c in impact.contacts if c.kind == "wall"):
            point = shape[c.point - 1]
            if planar:
                ax.plot(point[0], point[1], "r*", ms=8)
            else:
                ax.plot([point[0]], [point[2]], [point[1]], "r*", ms=8)
    from .animate import draw_box
    draw_box(ax, model.scene, planar)
    if not planar:
        for axis, setter in ((0, ax.set_xlim), (2, ax.set_ylim), (1, ax.set_zlim)):
            lo, hi = walls.get(f"x{axis + 1}_min"), walls.get(f"x{axis + 1}_max")
            if lo is not None and hi is not None:
                setter(lo, hi)
    ax.set_title(f"{model.scene.name}: configuration at each impact (red stars: contacts)")
    ax.legend(fontsize=6, loc="upper right")
    fig.tight_layout()
    path = out_dir / f"{model.scene.name}_impacts.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_all(model: CompiledModel, result: SimulationResult, out_dir: str | Path) -> list[Path]:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return plot_histories(model, result, out) + [plot_impact_configurations(model, result, out)]
