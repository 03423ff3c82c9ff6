"""Animations and film strips of a run: the chain in its box, frame by frame (matplotlib.animation).

    python -m runtime simulate --scene paper-case1 --animate case1.gif
    python -m runtime simulate --scene paper-case1 --film-strip strip.png --film-times 0,0.25,0.5,0.75,1.0

A planar run (every point stays in one plane X3 = const) is drawn in the X1-X2 plane, any other in 3D.  Each
frame shows the walls, the chain (points O_1..O_{n+1}), the time, and the points that touch a wall at an
impact within the frame's interval (red stars).  GIF is written by Pillow (a matplotlib dependency); MP4
needs ffmpeg on the PATH.  Frames are the run's samples, thinned to at most ``max_frames``.
"""
from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np

from codegen.scene import Scene, contact_points

MAX_FRAMES = 400


def animation_problem(path: str) -> str:
    """What keeps an animation from being written to ``path`` ('' when nothing does), checked before a run."""
    suffix = Path(path).suffix.lower()
    if suffix not in (".gif", ".mp4"):
        return f"--animate: the file must end in .gif or .mp4, got {path!r}"
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        return "--animate: .mp4 needs ffmpeg on the PATH (not found); write a .gif instead"
    return ""


def _shapes(result, scene: Scene, run=None) -> np.ndarray:
    """The points O_1..O_{n+1} at every sample: from the run's model at its parameters where given (a length set
    through p), else from the scene."""
    if run is None:
        return np.array([contact_points(scene, q) for q in result.q])
    return np.array([_points(q, run) for q in result.q])


def _points(q, run) -> np.ndarray:
    model, p = run
    return model.contact_points(model.layout.reduce(q), p)


def _run_values(model, p) -> dict | None:
    """The run's parameters by name, for drawing the walls and obstacles where the run had them (their places are
    runtime parameters); None: the scene's."""
    if model is None:
        return None
    return dict(zip(model.parameter_names, (model.parameters() if p is None else np.asarray(p, float)).tolist()))


def _lines(shape: np.ndarray, scene) -> np.ndarray:
    """The points as drawn: of several chains (codegen.scene.Chains), a NaN row between two chains breaks the line."""
    if isinstance(scene, Scene):
        return shape
    return np.insert(shape, [scene.point_offset(k) for k in range(2, len(scene.chains) + 1)], np.nan, axis=0)


CHAIN_COLORS = ["tab:blue", "tab:orange", "tab:green", "tab:purple"]     # a film strip's chains, in order


def _pieces(shape: np.ndarray, scene) -> list[np.ndarray]:
    """The points of each chain (one piece for a one-chain scene)."""
    if isinstance(scene, Scene):
        return [shape]
    return np.split(shape, [scene.point_offset(k) for k in range(2, len(scene.chains) + 1)])


def _planar(shapes: np.ndarray) -> bool:
    return bool(np.ptp(shapes[..., 2]) < 1e-9)


def _hull(points: np.ndarray) -> np.ndarray:
    """The convex hull of 2-D points, counter-clockwise (Andrew's monotone chain)."""
    pts = sorted(map(tuple, np.round(points, 15)))

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0.0:
                out.pop()
            out.append(p)
        return out[:-1]

    return np.array(half(pts) + half(pts[::-1]))


def box_corners(o) -> np.ndarray:
    """A box obstacle's 8 corners (box frame), corner k at the signs of k's bits."""
    R, h = np.array(o.box_rotation), np.array(o.half_extents)
    signs = np.array([[1 if k & (1 << j) else -1 for j in range(3)] for k in range(8)])
    return np.array(o.a) + (signs * h) @ R.T


def _draw_planes_obstacle(ax, scene: Scene, o, planar: bool) -> None:
    """A box: in the plane its outline projected there, in space its 12 edges; a plane: in the plane its trace at
    the chain's X3, in space a 2 m square of it about its point."""
    if o.kind == "box":
        corners = box_corners(o)
        if planar:
            outline = _hull(corners[:, :2])
            ax.fill(outline[:, 0], outline[:, 1], color="0.6", ec="0.3", lw=1.0, zorder=1)
        else:
            for k in range(8):
                for j in range(3):
                    if not k & (1 << j):
                        a, b = corners[k], corners[k | (1 << j)]
                        ax.plot([a[0], b[0]], [a[2], b[2]], [a[1], b[1]], color="0.4", lw=1.5)
        return
    n, p = np.array(o.normal), np.array(o.a)
    if planar:
        level = float(contact_points(scene, np.array(scene.q0))[0, 2])
        m = float(n[0] ** 2 + n[1] ** 2)
        if m > 0.0:                                          # its trace: n1 x + n2 y = n . p - n3 X3
            foot = (n @ p - n[2] * level) / m * n[:2]
            ax.axline(tuple(foot), tuple(foot + (-n[1], n[0])), color="0.3", lw=2.5, zorder=1)
    else:
        u = np.cross(n, (1.0, 0.0, 0.0) if abs(n[0]) < 0.9 else (0.0, 1.0, 0.0))
        u /= np.linalg.norm(u)
        v = np.cross(n, u)
        square = np.array([p + a * u + b * v for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1))])
        ax.plot(square[:, 0], square[:, 2], square[:, 1], color="0.4", lw=1.5)


def draw_obstacles(ax, scene: Scene, planar: bool, values: dict | None = None) -> None:
    """Each fixed obstacle, grey: in the plane its outline there (a disc for a sphere, a stadium for a bar: the
    capsule's section by the chain's plane X3 = const when both ends lie in it; a box's outline projected on it; a
    plane's trace), in space a capsule's axis as a thick line with its ends, a box's edges, a square of a plane.
    values: the run's parameters by name (_run_values), whose geometry entries place the obstacles."""
    for o in scene.obstacles:
        if values is not None:
            o = o.with_geometry([values.get(name, v) for name, v in zip(o.geometry_names, o.geometry_values)])
        if o.bounded_by_planes:
            _draw_planes_obstacle(ax, scene, o, planar)
            continue
        a, b = (np.array(x, dtype=float) for x in o.segment)
        if planar:
            turn = np.linspace(-np.pi / 2, np.pi / 2, 24)
            d = b[:2] - a[:2]
            angle = math.atan2(d[1], d[0]) if np.any(d) else 0.0
            ends = [(b[:2], angle + turn), (a[:2], angle + np.pi + turn)]
            outline = np.vstack([c + o.radius * np.column_stack([np.cos(t), np.sin(t)]) for c, t in ends])
            ax.fill(outline[:, 0], outline[:, 1], color="0.6", ec="0.3", lw=1.0, zorder=1)
        else:
            ax.plot([a[0], b[0]], [a[2], b[2]], [a[1], b[1]], color="0.5", lw=6, solid_capstyle="round")
            ax.plot([a[0], b[0]], [a[2], b[2]], [a[1], b[1]], "o", color="0.4", ms=5)


def draw_box(ax, scene: Scene, planar: bool, values: dict | None = None) -> None:
    """The walls (in the plane: the rectangle if all four exist, else each wall as a line), the fixed obstacles and
    axis labels; values: the run's parameters by name (their walls' places and obstacles' geometry)."""
    draw_obstacles(ax, scene, planar, values)
    walls = _walls(scene, values)
    if planar:
        lo1, hi1 = walls.get("x1_min"), walls.get("x1_max")
        lo2, hi2 = walls.get("x2_min"), walls.get("x2_max")
        if None not in (lo1, hi1, lo2, hi2):
            ax.plot([lo1, hi1, hi1, lo1, lo1], [lo2, lo2, hi2, hi2, lo2], "k-", lw=1.5)
        else:
            for x in (x for x in (lo1, hi1) if x is not None):
                ax.axvline(x, color="k", lw=1.5)
            for y in (y for y in (lo2, hi2) if y is not None):
                ax.axhline(y, color="k", lw=1.5)
        ax.set_aspect("equal")
        ax.set_xlabel("X1 (m)")
        ax.set_ylabel("X2 (m)")
        d = scene.gravity_direction
        if d != (0.0, -1.0, 0.0) and math.hypot(d[0], d[1]) > 0.0:    # a tilted gravity: its direction, drawn
            ax.annotate("g", xy=(0.88, 0.6), xycoords="axes fraction", xytext=(-30 * d[0], -30 * d[1]),
                        textcoords="offset points", ha="center", va="center", fontsize=8,
                        arrowprops={"arrowstyle": "->", "color": "0.3"})
    else:
        ax.set_xlabel("X1 (m)")
        ax.set_ylabel("X3 (m)")
        ax.set_zlabel("X2 (m)")


def _walls(scene: Scene, values: dict | None) -> dict:
    """Each wall's place: the run's parameter wall_<name> where given, else the scene's."""
    return {w.name: (values or {}).get(f"wall_{w.name}", w.position) for w in scene.walls}


def _limits(ax, shapes: np.ndarray, scene: Scene, planar: bool, values: dict | None = None) -> None:
    walls = _walls(scene, values)
    margin = 0.05 * max(float(np.ptp(shapes[..., :2])), 1e-3)
    for axis, setter in ((0, ax.set_xlim), (1, ax.set_ylim if planar else ax.set_zlim), (2, None if planar else ax.set_ylim)):
        if setter is None:
            continue
        lo = walls.get(f"x{axis + 1}_min", float(shapes[..., axis].min()))
        hi = walls.get(f"x{axis + 1}_max", float(shapes[..., axis].max()))
        setter(min(lo, float(shapes[..., axis].min())) - margin, max(hi, float(shapes[..., axis].max())) + margin)


def _draw(ax, shape, planar: bool, **style):
    if planar:
        return ax.plot(shape[:, 0], shape[:, 1], **style)[0]
    return ax.plot(shape[:, 0], shape[:, 2], shape[:, 1], **style)[0]


def animate(result, scene: Scene, path, fps: int = 30, max_frames: int = MAX_FRAMES, progress=None, model=None,
            p=None) -> int:
    """Write the run as an animation; returns the number of frames.  model, p: the run's model and parameters (the
    links, walls and obstacles then drawn as the run had them, where p moved them); None: the scene's values."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation
    if len(result.t) == 0:
        raise ValueError("--animate: the run has no samples to draw")
    run, values = (None if model is None else (model, p)), _run_values(model, p)
    shapes = _shapes(result, scene, run)
    frames = np.unique(np.linspace(0, len(result.t) - 1, min(max_frames, len(result.t))).round().astype(int))
    planar = _planar(shapes)
    fig = plt.figure(figsize=(6.4, 4.8))
    ax = fig.add_subplot(111) if planar else fig.add_subplot(111, projection="3d")
    draw_box(ax, scene, planar, values)
    _limits(ax, shapes, scene, planar, values)
    chain = _draw(ax, _lines(shapes[0], scene), planar, color="tab:blue", marker="o", ms=4, lw=2)
    stars = _draw(ax, shapes[0][:0], planar, color="r", marker="*", ms=12, ls="none")
    label = ax.set_title("")
    impact_t = np.array([i.t for i in result.impacts])

    def update(k):
        i = frames[k]
        shape = _lines(shapes[i], scene)
        if planar:
            chain.set_data(shape[:, 0], shape[:, 1])
        else:
            chain.set_data_3d(shape[:, 0], shape[:, 2], shape[:, 1])
        t_prev = result.t[frames[k - 1]] if k > 0 else -np.inf
        hits = [imp for imp, t in zip(result.impacts, impact_t) if t_prev < t <= result.t[i]]
        points = np.array([(contact_points(scene, imp.q) if run is None else _points(imp.q, run))[c.point - 1]
                           for imp in hits for c in imp.contacts if c.kind == "wall"]).reshape(-1, 3)
        if planar:
            stars.set_data(points[:, 0], points[:, 1])
        else:
            stars.set_data_3d(points[:, 0], points[:, 2], points[:, 1])
        label.set_text(f"{scene.name}   t = {result.t[i]:.3f} s" + (f"   impact ({len(hits)})" if hits else ""))
        if progress and k % 50 == 0:
            progress(f"frame {k + 1}/{len(frames)}")
        return chain, stars, label

    movie = animation.FuncAnimation(fig, update, frames=len(frames), blit=False)
    writer = animation.PillowWriter(fps=fps) if str(path).lower().endswith(".gif") else animation.FFMpegWriter(fps=fps)
    movie.save(str(path), writer=writer)
    plt.close(fig)
    return len(frames)


def film_strip(result, scene: Scene, path, times, model=None, p=None) -> None:
    """The chain at the chosen times, side by side (as the paper's Fig. 14 A-E), from the nearest samples; model, p
    as animate's."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    run, values = (None if model is None else (model, p)), _run_values(model, p)
    shapes = _shapes(result, scene, run)
    planar = _planar(shapes)
    fig = plt.figure(figsize=(3.0 * len(times), 3.2))
    for k, t in enumerate(times):
        i = int(np.argmin(np.abs(result.t - t)))
        ax = fig.add_subplot(1, len(times), k + 1, **({} if planar else {"projection": "3d"}))
        draw_box(ax, scene, planar, values)
        _limits(ax, shapes, scene, planar, values)
        for piece, color in zip(_pieces(shapes[i], scene), CHAIN_COLORS * len(shapes[i])):
            _draw(ax, piece, planar, color=color, marker="o", ms=3, lw=2)
        ax.set_title(f"{chr(ord('A') + k) if k < 26 else k}: t = {result.t[i]:.3f} s", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
