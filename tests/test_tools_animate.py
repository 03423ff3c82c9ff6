"""Animations and film strips of a run (runtime.animate, simulate --animate / --film-strip)."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from runtime import simulate
from conftest import quick_model

ROOT = Path(__file__).resolve().parent.parent
Image = pytest.importorskip("PIL.Image", reason="Pillow (a matplotlib dependency) is not installed")


@pytest.mark.parametrize("scene", ["paper-case1", "paper-case2"])     # planar (2D view) and spatial (3D view)
def test_animation_has_a_frame_per_sample(tmp_path, scene):
    from runtime.animate import animate
    model = quick_model(scene)
    result = simulate(model, 0.3, t_eval=np.linspace(0, 0.3, 13))
    frames = animate(result, model.scene, tmp_path / "run.gif", fps=10)
    with Image.open(tmp_path / "run.gif") as gif:
        assert frames == 13 and gif.n_frames == 13


def test_frames_are_thinned_to_the_limit(tmp_path):
    from runtime.animate import animate
    model = quick_model("paper-case1")
    result = simulate(model, 0.5, t_eval=np.linspace(0, 0.5, 101))
    assert animate(result, model.scene, tmp_path / "run.gif", max_frames=20) == 20


def test_simulate_command_animates_and_draws_a_film_strip(tmp_path):
    done = subprocess.run([sys.executable, "-m", "runtime", "simulate", "--scene", "driven-fold", "--t-end", "0.2",
                           "--samples-dt", "0.02", "--animate", str(tmp_path / "a.gif"), "--film-strip",
                           str(tmp_path / "s.png"), "--film-times", "0,0.1,0.2"], cwd=ROOT, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    assert "(11 frames)" in done.stdout
    with Image.open(tmp_path / "s.png") as png:
        assert png.size[0] > 2 * png.size[1]          # three panels side by side


@pytest.mark.parametrize("args,message", [
    (["--animate", "x.avi"], "--animate: the file must end in .gif or .mp4"),
    (["--animate", "x.gif", "--fps", "0"], "--fps: must be in 1..120"),
    (["--film-strip", "s.png", "--film-times", "0,9"], "--film-times: 1 to 26 times within [0, t_end = 1.5] s"),
    (["--film-strip", "s.png", "--film-times", "a"], "--film-times: expected times in s separated by commas"),
])
def test_bad_animation_arguments(tmp_path, args, message):
    done = subprocess.run([sys.executable, "-m", "runtime", "simulate", "--scene", "paper-case1", *args],
                          cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert not list(tmp_path.iterdir())


def test_a_run_is_drawn_where_its_parameters_put_it(tmp_path):
    """Link lengths, walls' places and obstacles' geometry are runtime parameters: a run with them moved through p
    is drawn with them there (the points from the model at p, the walls and obstacles from p), not at the scene's."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from codegen.scene import load_scene
    from runtime.animate import _run_values, _shapes, _walls, draw_obstacles, film_strip
    model = quick_model("paper-case1")
    names = model.parameter_names
    l_1 = 0.8 * model.parameters()[names.index("l_1")]
    p = model.parameters({"l_1": l_1, "wall_x2_min": -0.3})
    result = simulate(model, 0.2, p=p, t_eval=np.linspace(0, 0.2, 5))
    shapes = _shapes(result, model.scene, (model, p))
    assert np.linalg.norm(shapes[:, 1] - shapes[:, 0], axis=1) == pytest.approx(l_1, rel=1e-12)
    assert _walls(model.scene, _run_values(model, p))["x2_min"] == -0.3
    assert _walls(model.scene, None)["x2_min"] == model.scene.wall("x2_min").position
    film_strip(result, model.scene, tmp_path / "s.png", [0.0, 0.2], model=model, p=p)
    assert (tmp_path / "s.png").stat().st_size > 0
    scene = load_scene("arm-obstacle")
    ball = scene.obstacles[0]
    fig, ax = plt.subplots()
    draw_obstacles(ax, scene, True, {f"center_x_{ball.name}": ball.a[0] + 1.0})
    outline = ax.patches[0].get_path().vertices
    assert outline[:, 0].mean() == pytest.approx(ball.a[0] + 1.0, abs=0.2 * ball.radius)
    plt.close(fig)
