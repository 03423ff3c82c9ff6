"""python -m studies STUDY [options]: one entry point for every study; each study parses its own options
(``python -m studies STUDY --help``)."""
from __future__ import annotations

import argparse
import importlib
import sys

# study -> (module, one line for --help); each module has main(argv) -> exit code
STUDIES = {
    "ops": ("studies.opscount", "operation counts and rhs times, Gibbs-Appell against Lagrange"),
    "scaling": ("studies.scaling", "generator stage times and operation counts against n"),
    "embed": ("studies.embed_report", "the embeddable C: object size, stack use, ms per simulated second"),
    "precision": ("studies.precision", "work-precision: error against CPU time of every integrator"),
    "stress": ("studies.stress_suite", "the stress suite: stiff and extreme scenes, pass/fail table"),
    "fuzz": ("studies.fuzz", "random admissible scenes through the hybrid loop, each run checked"),
    "benchmark": ("studies.benchmark", "the compiled hybrid loop against scipy's solve_ivp with events"),
    "charts": ("studies.charts_report", "chart switching near the gimbal lock, against an independent run"),
    "specialise": ("studies.specialise_report", "general against specialised models on the paper's scenes"),
    "ensemble": ("studies.ensemble_bench", "runs per second of simulate_many: threads, processes, Dask"),
    "driven": ("studies.driven_cost", "the cost of inputs, springs and dampers: ns per rhs, simulation time"),
    "simcost": ("studies.simcost", "time per simulated second against n, with the fitted exponent"),
    "peer": ("studies.peer", "forward dynamics against Pinocchio's ABA traced by CasADi, side by side in C"),
    "friction": ("studies.friction_cost", "friction at resting contacts: cost and the regularisation velocity"),
    "links": ("studies.link_cost", "link-link contacts: a capsule scene with and without its link pairs"),
    "fmu": ("studies.fmu_cost", "a run through the FMI 2.0 FMU (driven by FMPy) against runtime.simulate"),
    "identify": ("studies.identify_restitution", "restitution and g fitted to noisy impact times, exact Jacobian"),
    "shoot": ("studies.shoot_target", "the throw whose tip hits a target after a bounce, Newton with exact Jacobians"),
    "sensitivities": ("studies.sens_cost", "a run's sensitivities along k directions against the plain run"),
}


def parse_links(text: str, low: int = 1) -> list[int]:
    """A study's --links: '1-8', '1,2,4', '1-4,8,16' -> sorted distinct n, each in low..MAX_LINKS; ValueError
    naming the option and the range otherwise."""
    from codegen.scene import MAX_LINKS
    ns = set()
    try:
        for part in text.split(","):
            part = part.strip()
            if "-" in part:
                lo, hi = (int(x) for x in part.split("-", 1))
                if lo > hi:
                    raise ValueError
                ns.update(range(lo, hi + 1))
            else:
                ns.add(int(part))
    except ValueError:
        raise ValueError(f"--links: expected a range like 1-8 or a list like 1,2,4, got {text!r}") from None
    bad = [n for n in ns if not low <= n <= MAX_LINKS]
    if bad or not ns:
        raise ValueError(f"--links: every n must be in {low}..{MAX_LINKS}, got {text!r}")
    return sorted(ns)


def build_parser() -> argparse.ArgumentParser:
    width = max(map(len, STUDIES)) + 2
    parser = argparse.ArgumentParser(
        prog="python -m studies", usage="python -m studies [-h] STUDY [options]",
        description="Studies and reports on the generated models (the 'study' extra: pip install -e \".[study]\").",
        epilog="studies:\n" + "".join(f"  {name:{width}}{summary}\n" for name, (_, summary) in STUDIES.items())
               + "\nOptions of a study: python -m studies STUDY --help",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="study", metavar="STUDY", required=True, help=argparse.SUPPRESS)
    for name in STUDIES:
        commands.add_parser(name, add_help=False)                   # the study's own parser takes the rest
    return parser


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = build_parser().parse_args(argv[:1])                     # the study's name (or --help)
    module = importlib.import_module(STUDIES[args.study][0])
    return module.main(argv[1:])
