"""Identification from impact times: a tilted rod dropped onto a floor bounces from one end to the other; from its
first impact times, measured with noise, fit the floor's restitution e and gravity g by least squares
(scipy.optimize.least_squares), once with the exact Jacobian of the impact times (simulate(sensitivities=...),
each impact's dt_dp) and once with finite-difference Jacobians, and compare iterations, runs, time and error.

    python -m studies identify [--impacts 8] [--noise 1e-4] [--seed 1] [--plot identify.png]

The impact times t_i(e, g) are smooth in (e, g) while the sequence of impacts (which end strikes, in which order)
stays the same; the fit starts close enough for that (the residuals of runs with fewer impacts are padded).
"""
from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

TRUE = {"e_x2_min": 0.8, "g": 9.81}
START = {"e_x2_min": 0.65, "g": 8.5}
NAMES = ("e_x2_min", "g")
T_END = 3.0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies identify", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--impacts", type=int, default=8, help="impact times measured (default 8)")
    parser.add_argument("--noise", type=float, default=1e-4, help="standard deviation of the timing noise, s "
                        "(default 1e-4)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the noise (default 1)")
    parser.add_argument("--plot", metavar="PNG", help="draw the measured and fitted impact times and heights")
    return parser


def rod_scene():
    """A uniform slender rod, 1 m and 1 kg, its lower end O_1 0.6 m above the floor x2_min = 0, tilted 1 rad
    from the vertical and falling from rest: every impact of one end turns it and the other end strikes next."""
    from codegen.scene import scene_from_dict
    return scene_from_dict({"name": "identify_rod", "gravity": TRUE["g"],
                            "links": [{"length": 1.0, "mu": 1.0, "J": [0.0, 0.0, 0.0]}],
                            "walls": {"x2_min": 0.0}, "restitution": TRUE["e_x2_min"],
                            "initial": {"q": [-math.pi / 2, 0.0, 1.0, 0.0, 0.6, 0.0],
                                        "qd": [0.0] * 6}})


class ImpactTimes:
    """t_i(e, g) of the first `count` impacts of the rod, and their Jacobian, counting the runs."""

    def __init__(self, model, count: int):
        self.model, self.count, self.runs = model, count, 0

    def _run(self, x, sensitivities=None):
        from runtime import simulate
        self.runs += 1
        p = self.model.parameters(dict(zip(NAMES, x)))
        return simulate(self.model, T_END, p=p, max_impacts=self.count, rtol=1e-11, atol=1e-12, rest_height=0.0,
                        zeno_impacts=0, sensitivities=sensitivities)

    def times(self, x):
        r = self._run(x)
        t = [i.t for i in r.impacts][:self.count]
        return np.array(t + [T_END] * (self.count - len(t)))          # too few impacts: padded

    def jacobian(self, x):
        r = self._run(x, sensitivities=list(NAMES))
        rows = [[i.dt_dp[n] for n in NAMES] for i in r.impacts][:self.count]
        return np.array(rows + [[0.0, 0.0]] * (self.count - len(rows)))


def fit(model, measured: np.ndarray, exact: bool) -> dict:
    """least_squares on the impact times from START: the exact Jacobian (exact) or scipy's 2-point differences."""
    from scipy.optimize import least_squares
    f = ImpactTimes(model, len(measured))
    start = time.perf_counter()
    out = least_squares(lambda x: f.times(x) - measured, [START[n] for n in NAMES],
                        jac=(lambda x: f.jacobian(x)) if exact else "2-point", x_scale=[0.1, 1.0], xtol=1e-12,
                        ftol=1e-12, gtol=1e-12, bounds=([0.05, 1.0], [1.0, 30.0]))
    return {"x": out.x, "nfev": out.nfev, "njev": out.njev, "runs": f.runs, "seconds": time.perf_counter() - start,
            "cost": out.cost, "rms": math.sqrt(2 * out.cost / len(measured)), "status": out.status}


def identify(impacts: int = 8, noise: float = 1e-4, seed: int = 1):
    """Measure, fit both ways: (model, measured impact times, true times, {"exact": fit, "differences": fit})."""
    from runtime import load_model
    model = load_model(rod_scene(), specialise=True, tangent=True)
    truth = ImpactTimes(model, impacts).times([TRUE[n] for n in NAMES])
    measured = truth + np.random.default_rng(seed).normal(0.0, noise, impacts)
    return model, measured, truth, {"exact": fit(model, measured, True), "differences": fit(model, measured, False)}


def plot(path: str, model, measured, fits) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from runtime import simulate
    fig, ax = plt.subplots(figsize=(8, 4))
    for label, x, style in (("start", [START[n] for n in NAMES], ":"), ("fit (exact Jacobian)", fits["exact"]["x"], "-")):
        r = simulate(model, T_END, p=model.parameters(dict(zip(NAMES, x))), t_eval=np.linspace(0, T_END, 1500),
                     max_impacts=len(measured), rest_height=0.0, zeno_impacts=0, rtol=1e-10, atol=1e-12)
        ax.plot(r.t, r.q[:, 4], style, label=f"{label}: e = {x[0]:.4f}, g = {x[1]:.4f}")
    for t in measured:
        ax.axvline(t, color="0.6", lw=0.6)
    ax.plot(measured, np.zeros_like(measured), "kv", label="measured impact times")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("height of the end O_1 (m)")
    ax.set_xlim(0, measured[-1] + 0.1)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    if args.impacts < 2 or not args.noise >= 0.0:
        print("--impacts: at least 2; --noise: >= 0", file=sys.stderr)
        return 2
    model, measured, truth, fits = identify(args.impacts, args.noise, args.seed)
    print(f"true e = {TRUE['e_x2_min']}, g = {TRUE['g']}; start e = {START['e_x2_min']}, g = {START['g']}; "
          f"{args.impacts} impact times, noise {args.noise:g} s")
    print("Jacobian     | e          | g          | runs | Jacobians | time (s) | rms residual (s)")
    for name, f in fits.items():
        print(f"{name:12} | {f['x'][0]:.8f} | {f['x'][1]:.8f} | {f['runs']:4d} | {f['njev']:9d} | "
              f"{f['seconds']:8.3f} | {f['rms']:.3e}")
    if args.plot:
        plot(args.plot, model, measured, fits)
        print(f"wrote {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
