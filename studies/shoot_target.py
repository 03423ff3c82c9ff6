"""Shooting through impacts: the initial velocity of a thrown 2-link chain's base (qd0 of X1, X2, X3) that makes its
tip O_3 reach a target point at a given time, after the chain has bounced off the floor, by Newton's method with the
exact Jacobian d tip(T) / d qd0 = J_tip(q(T)) S_q(T) (simulate(sensitivities=...), whose S carries the impacts'
jumps).

    python -m studies shoot [--t 1.2] [--target 0.6,0.5,1.1]

The default target is where the tip of a throw at qd0 = (1, 2, 0.5) m/s is at t = 1.2 s; Newton starts from
(0.6, 2.4, 0.2) m/s and may find another throw that puts the tip there (the map is not one-to-one).  Each iterate
must meet the same impacts (the map is smooth only while they stay the same).
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

DIRECTIONS = ("qd0[X1]", "qd0[X2]", "qd0[X3]")
TRUE = (1.0, 2.0, 0.5)
START = (0.6, 2.4, 0.2)
OPTIONS = dict(rtol=1e-11, atol=1e-12)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies shoot", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--t", type=float, default=1.2, help="time at which the tip is to be at the target, s "
                        "(default 1.2)")
    parser.add_argument("--target", help="the target point X1,X2,X3 in m (default: where the throw at qd0 = "
                        "(1, 2, 0.5) puts the tip at --t)")
    return parser


def chain_scene():
    """Two slender links (0.8 m and 0.6 m, 1 kg each) above the floor x2_min = 0 (restitution 0.9), their base O_1
    at height 1.5 m, both joints turning: thrown, the chain strikes the floor with O_1, O_2 and O_3 in turn."""
    from codegen.scene import scene_from_dict
    return scene_from_dict({"name": "shoot_chain", "gravity": 9.81,
                            "links": [{"length": 0.8, "mu": 1.0, "J": [0.01, 0.01, 0.01]},
                                      {"length": 0.6, "mu": 1.0, "J": [0.01, 0.01, 0.01]}],
                            "walls": {"x2_min": 0.0}, "restitution": 0.9,
                            "initial": {"q": [0.0, 0.0, 0.27, -0.69, 0.0, 1.5, 0.0],
                                        "qd": [0.0, 0.0, -0.92, -0.97, *TRUE]}})


def tip(model, t: float, velocity, sensitivities: bool = False):
    """The tip O_{n+1} at time t for the base velocity (X1, X2, X3), its Jacobian by the velocity (3 x 3, when
    ``sensitivities``) and the run's impacts (contact labels)."""
    from runtime import simulate
    qd0 = np.array(model.qd0, dtype=float)
    qd0[-3:] = velocity
    r = simulate(model, t, qd0=qd0, sensitivities=list(DIRECTIONS) if sensitivities else None, **OPTIONS)
    if not r.success:
        raise RuntimeError(r.message)
    q = model.layout.reduce(r.q_final)
    point = model.contact_points(q)[-1]
    impacts = [tuple(c.label for c in i.contacts) for i in r.impacts]
    if not sensitivities:
        return point, None, impacts
    s = r.sensitivities
    if not s.valid:
        raise RuntimeError(s.message)
    nq = model.nq
    jac = np.column_stack([model.contact_velocities(q, s.matrix[:nq, j])[-1] for j in range(len(DIRECTIONS))])
    return point, jac, impacts


def shoot(model, t: float, target, start=START, tol: float = 1e-10, max_iterations: int = 12):
    """Newton's method on tip(t; v) = target from ``start``: (v, history of (|residual| m, impacts))."""
    v = np.array(start, dtype=float)
    history = []
    for _ in range(max_iterations):
        point, jac, impacts = tip(model, t, v, sensitivities=True)
        residual = point - target
        history.append((float(np.linalg.norm(residual)), impacts))
        if history[-1][0] <= tol:
            break
        v = v - np.linalg.solve(jac, residual)
    return v, history


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from runtime import load_model
    model = load_model(chain_scene(), tangent=True)
    if args.target is None:
        target = tip(model, args.t, TRUE)[0]
    else:
        try:
            target = np.array([float(x) for x in args.target.split(",")])
            assert target.shape == (3,)
        except (ValueError, AssertionError):
            print(f"--target: expected three numbers X1,X2,X3 (m), got {args.target!r}", file=sys.stderr)
            return 2
    v, history = shoot(model, args.t, target)
    print(f"target {np.array2string(target, precision=6)} m at t = {args.t} s; start qd0 = {START} m/s")
    for k, (size, impacts) in enumerate(history):
        print(f"  iteration {k}: |tip - target| = {size:.3e} m, impacts {' '.join('+'.join(c) for c in impacts)}")
    print(f"qd0 (X1, X2, X3) = {np.array2string(v, precision=10)} m/s")
    return 0 if history[-1][0] <= 1e-10 else 1


if __name__ == "__main__":
    sys.exit(main())
