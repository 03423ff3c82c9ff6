"""Plots that stay readable: every varied quantity of a sweep is drawn, impacts are coloured by time with a colour
bar, long chains get a colour bar instead of a long legend, and a 3D run gets its X3 histories.  The checks read
the artists matplotlib drew (Agg), taken from each figure as it is saved."""
import itertools

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib", reason="matplotlib is not installed (the plot extra)")
matplotlib.use("Agg")
import matplotlib.figure  # noqa: E402
from matplotlib.collections import PathCollection, QuadMesh  # noqa: E402

from codegen.scene import contact_points, default_scene  # noqa: E402
from runtime import simulate  # noqa: E402
from runtime.ensemble import Ensemble  # noqa: E402
from runtime.plots import plot_all  # noqa: E402
from runtime.sweep import Vary, build_runs, check_names, plot_sweep  # noqa: E402
from conftest import quick_model


@pytest.fixture
def saved(monkeypatch):
    """The figures written by Figure.savefig during the test, in order."""
    figures = []
    save = matplotlib.figure.Figure.savefig

    def keep(self, *args, **kwargs):
        figures.append(self)
        return save(self, *args, **kwargs)
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", keep)
    return figures


def legend_sizes(figure) -> list[int]:
    return [len(ax.get_legend().get_texts()) for ax in figure.axes if ax.get_legend() is not None]


def colour_bar_labels(figure) -> list[str]:
    """The labels of the figure's colour bars (matplotlib names a colour bar's axes '<colorbar>')."""
    return [ax.get_ylabel() for ax in figure.axes if ax.get_label() == "<colorbar>"]


def drawn(figure, kind) -> list:
    """(axes, collection) of every collection of this kind on the figure's plotting axes (not its colour bars)."""
    return [(ax, c) for ax in figure.axes if ax.get_label() != "<colorbar>" for c in ax.collections
            if isinstance(c, kind)]


# ---------------------------------------------------------------------------------------------------------------
# sweeps
# ---------------------------------------------------------------------------------------------------------------
def study(varies, samples=None, seed=0):
    """A sweep's table without running anything: the impacts of a grid run are 100 i + 10 j + k (i, j, k the
    indices of its values), the final energy the sum of the varied values."""
    rows = []
    indices = list(itertools.product(*(range(v.count) for v in varies)))
    for number, run in enumerate(build_runs(varies, samples, seed)):
        values = [run["p"]["e_x2_min"], run["qd0"]["X1"], run["q0"]["theta_2"]][:len(varies)]
        row = {"run": number, "p.e_x2_min": values[0], "qd.X1": values[1], "q.theta_2": values[2],
               "status": 0, "message": "reached t_end", "energy_final": float(sum(values))}
        row["n_impacts"] = 0 if samples else int(np.dot(indices[number], (100, 10, 1)))
        rows.append(row)
    return Ensemble(rows)


VARIES = [Vary("e_x2_min", 0.2, 1.0, 3), Vary("qd.X1", -1.0, 1.0, 4), Vary("q.theta_2", -0.1, 0.1, 2)]


def test_a_grid_of_three_varies_draws_one_heat_map_per_value_of_the_third(saved, tmp_path):
    """Three --vary on a grid: a heat map over the two with the most values (e_x2_min down, qd.X1 across) for each
    value of the third, per quantity; each holds exactly its own runs, and nothing is drawn as a scatter."""
    plot_sweep(study(VARIES), VARIES, tmp_path / "sweep.png")
    figure, = saved
    meshes = drawn(figure, QuadMesh)
    assert len(meshes) == 2 * 2                                     # (impacts, energy) x 2 values of theta_2
    assert drawn(figure, PathCollection) == []
    impacts = {ax.get_title(): np.asarray(mesh.get_array()).reshape(3, 4) for ax, mesh in meshes
               if np.asarray(mesh.get_array()).max() > 10}
    assert sorted(impacts) == ["q.theta_2 = -0.1", "q.theta_2 = 0.1"]
    for k, title in enumerate(sorted(impacts)):
        expected = np.array([[100 * i + 10 * j + k for j in range(4)] for i in range(3)])
        assert np.array_equal(impacts[title], expected), title
    assert sorted(colour_bar_labels(figure)) == ["final energy (J)", "impacts"]


def test_random_samples_of_three_varies_are_split_into_bins_of_the_third(saved, tmp_path):
    """--samples with three --vary: scatter panels over the first two, one per bin of the third's range; every run
    in exactly one panel of each quantity, inside its panel's bin."""
    plot_sweep(study(VARIES, samples=200, seed=3), VARIES, tmp_path / "sweep.png")
    figure, = saved
    panels = drawn(figure, PathCollection)
    assert len(panels) == 2 * 4
    assert sum(len(c.get_offsets()) for _, c in panels) == 2 * 200
    energies = [(ax, c) for ax, c in panels if np.any(np.asarray(c.get_array()) != 0)]     # the impacts are 0
    assert len(energies) == 4
    for ax, collection in energies:                 # energy = e_x2_min + qd.X1 + theta_2 gives theta_2 back
        low, high = (float(x) for x in ax.get_title().split("[")[1].rstrip("])").split(","))
        x, y = collection.get_offsets().T
        theta_2 = np.asarray(collection.get_array()) - x - y
        assert np.all((theta_2 >= low - 1e-9) & (theta_2 <= high + 1e-9)), ax.get_title()


def test_more_varies_than_the_plot_can_draw_are_refused():
    varies = [Vary(name, 0.0, 1.0, 2) for name in ("g", "q.X1", "q.X2", "q.X3", "qd.X1", "qd.X2", "qd.X3")]
    with pytest.raises(ValueError, match="--vary: at most 6 varied quantities"):
        check_names(varies, ["g"], 4)


# ---------------------------------------------------------------------------------------------------------------
# single runs
# ---------------------------------------------------------------------------------------------------------------
def test_a_hundred_impacts_are_coloured_by_time_not_listed_in_a_legend(saved, tmp_path):
    """paper-case2 over 10 s has more than 100 impacts: one colour bar of the impact time, a legend of at most two
    entries (the start, the touching points), and each impact's configuration coloured by its time."""
    model = quick_model("paper-case2", chart_b=True)             # a tumbling link: it passes the gimbal lock
    result = simulate(model, 10.0, t_eval=np.linspace(0.0, 10.0, 201))
    assert len(result.impacts) >= 100
    plot_all(model, result, tmp_path)
    figure = saved[-1]
    assert colour_bar_labels(figure) == ["time of the impact (s)"]
    assert legend_sizes(figure) == [2]
    ax = figure.axes[0]
    chains = [line for line in ax.get_lines() if len(line.get_data_3d()[0]) == 2 and line.get_linestyle() == "-"]
    assert len(chains) == len(result.impacts)
    colours = [matplotlib.colors.to_rgba(line.get_color()) for line in chains]
    expected = [matplotlib.colormaps["viridis"](impact.t / 10.0) for impact in result.impacts]
    assert np.allclose(colours, expected, atol=1e-2)


def test_a_3d_run_gets_its_x3_histories(saved, tmp_path):
    """paper-case2 leaves the plane: positions and velocities along X3 are drawn too, the positions being the
    points' X3 of the scene's own forward kinematics; a planar run keeps its five histories."""
    model = quick_model("paper-case2", chart_b=True)
    result = simulate(model, 0.5, t_eval=np.linspace(0.0, 0.5, 51))
    names = [path.name for path in plot_all(model, result, tmp_path / "case2")]
    assert "paper_case2_positions_X3.png" in names and "paper_case2_velocities_X3.png" in names
    figure = saved[names.index("paper_case2_positions_X3.png")]
    expected = np.array([contact_points(model.scene, q)[:, 2] for q in result.q])
    lines = figure.axes[0].get_lines()
    curves = [line for line in lines if len(line.get_ydata()) == len(result.t)]
    assert len(curves) == 2
    for i, line in enumerate(curves):
        assert np.allclose(line.get_ydata(), expected[:, i], rtol=0, atol=1e-12)
    assert np.ptp(expected) > 0.1
    planar = quick_model("paper-case1")
    names = [path.name for path in plot_all(planar, simulate(planar, 0.3), tmp_path / "case1")]
    assert not any("X3" in name for name in names) and len(names) == 6


def test_a_long_chain_gets_a_colour_bar_instead_of_a_long_legend(saved, tmp_path):
    """Nine links: eleven angles are coloured by their index with a colour bar; no legend anywhere holds more than
    the ten entries the colour cycle can tell apart."""
    model = quick_model(default_scene(9))
    plot_all(model, simulate(model, 0.2), tmp_path)
    assert all(size <= 10 for figure in saved for size in legend_sizes(figure))
    angles = saved[0]
    assert colour_bar_labels(angles) == ["k (the curve of θk)"] and legend_sizes(angles) == []
    assert len(angles.axes[0].get_lines()) == 9 + 2
