"""A run's samples as files: CSV (one row per sample) and NPZ (arrays, with the impacts).

Columns / arrays: t (s); q.NAME and qd.NAME for every coordinate of Eq. 13 (rad, m; rad/s, m/s);
u.NAME for the inputs of a driven model (N m, N); O{i}.X1 .. O{i}.X3 the joint points O_1 .. O_{n+1} (m),
from the sampled configuration (codegen.scene.contact_points).  The NPZ also holds the impacts: their
times, and the state before and after each.
"""
from __future__ import annotations

import csv

import numpy as np

from codegen.scene import Scene, contact_points, coordinate_names


def sample_table(result, scene: Scene) -> tuple[list[str], np.ndarray]:
    """(column names, samples x columns array) of a SimulationResult."""
    names = coordinate_names(scene.n)
    columns = ["t"] + [f"q.{c}" for c in names] + [f"qd.{c}" for c in names]
    blocks = [result.t[:, None], result.q, result.qd]
    if getattr(result, "u", None) is not None and len(scene.inputs):
        columns += [f"u.{c}" for c in scene.inputs]
        blocks.append(result.u)
    points = joint_points(result, scene)
    columns += [f"O{i}.X{a}" for i in range(1, scene.n + 2) for a in (1, 2, 3)]
    blocks.append(points.reshape(len(result.t), -1))
    return columns, np.hstack(blocks) if len(result.t) else np.zeros((0, len(columns)))


def joint_points(result, scene: Scene) -> np.ndarray:
    """O_1 .. O_{n+1} at every sample: samples x (n + 1) x 3 (m)."""
    return np.array([contact_points(scene, q) for q in result.q]).reshape(len(result.t), scene.n + 1, 3)


def write_csv(result, path, scene: Scene) -> None:
    columns, table = sample_table(result, scene)
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        for row in table:
            writer.writerow([repr(float(x)) for x in row])


def write_npz(result, path, scene: Scene) -> None:
    columns, table = sample_table(result, scene)
    impacts = result.impacts
    np.savez(path, columns=np.array(columns), samples=table, t=result.t, q=result.q, qd=result.qd,
             points=joint_points(result, scene),
             impact_t=np.array([i.t for i in impacts]),
             impact_q=np.array([i.q for i in impacts]).reshape(len(impacts), -1),
             impact_qd_before=np.array([i.qd_before for i in impacts]).reshape(len(impacts), -1),
             impact_qd_after=np.array([i.qd_after for i in impacts]).reshape(len(impacts), -1),
             impact_contacts=np.array([", ".join(c.label for c in i.contacts) for i in impacts]))
