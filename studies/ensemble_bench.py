"""Throughput of runtime.ensemble.simulate_many: runs per second of a shipped scene (a sweep of the floor's
restitution) serially, on local threads, on local processes and on a Dask LocalCluster of worker processes,
side by side in one run and repeated; the Dask overhead per task; the memory of many summary rows.

    python -m studies ensemble [--scene paper-case1] [--runs 10000] [--t-end 1.5] [--workers 2] [--repeats 2]
"""
from __future__ import annotations

import argparse
import sys
import time
import tracemalloc

import numpy as np

from .machine import describe


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies ensemble", description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="paper-case1", help="shipped scene or scene file (default paper-case1)")
    parser.add_argument("--runs", type=int, default=10000, help="runs per measurement (default 10000)")
    parser.add_argument("--t-end", type=float, default=1.5, help="simulated time of each run in s (default 1.5)")
    parser.add_argument("--workers", type=int, default=2, help="threads / processes / Dask workers (default 2)")
    parser.add_argument("--repeats", type=int, default=2, help="repeats of each measurement (default 2)")
    parser.add_argument("--memory-runs", type=int, default=20000,
                        help="rows for the memory measurement (default 20000; tracemalloc slows the runs)")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    if args.runs < 1 or args.workers < 1 or args.repeats < 1 or args.memory_runs < 1 or not args.t_end > 0:
        print("error: --runs, --workers, --repeats, --memory-runs >= 1 and --t-end > 0", file=sys.stderr)
        return 2
    from runtime import load_model
    from runtime.ensemble import simulate_many
    model = load_model(args.scene)
    names = model.parameter_names
    restitution = "e_x2_min" if "e_x2_min" in names else next(name for name in names if name.startswith("e_"))
    runs = [{"p": {restitution: e}} for e in np.linspace(0.1, 1.0, args.runs)]
    ways = {"serial": dict(workers=1), f"{args.workers} threads": dict(workers=args.workers),
            f"{args.workers} processes": dict(workers=args.workers, processes=True)}
    seconds = {name: [] for name in list(ways) + [f"Dask LocalCluster, {args.workers} processes"]}
    reference = None
    try:
        from distributed import Client, LocalCluster
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    except ModuleNotFoundError:
        client = None
        print("  (dask.distributed is not installed: no Dask row; pip install -e \".[ensemble]\")", file=sys.stderr)
    for repeat in range(args.repeats):
        for name, how in ways.items():
            study = simulate_many(model, runs, args.t_end, t_eval=[], **how)
            seconds[name].append(study.seconds)
            reference = reference or study.rows
            assert study.rows == reference, f"{name}: rows differ from the serial ones"
            print(f"  repeat {repeat + 1}: {name} {study.seconds:.2f} s", file=sys.stderr, flush=True)
        if client is not None:
            name = f"Dask LocalCluster, {args.workers} processes"
            study = simulate_many(model, runs, args.t_end, t_eval=[], client=client)
            seconds[name].append(study.seconds)
            assert study.rows == reference, "Dask: rows differ from the serial ones"
            print(f"  repeat {repeat + 1}: {name} {study.seconds:.2f} s", file=sys.stderr, flush=True)
    impacts = np.mean([row["n_impacts"] for row in reference])
    print(f"Machine: {describe()}")
    print(f"{args.scene}, {args.runs:,} runs of {args.t_end} s ({restitution} from 0.1 to 1, {impacts:.1f} impacts "
          f"per run on average), {args.repeats} repeats:\n")
    print("| how | runs/s, median (min-max) | speed-up |")
    print("|---|---|---|")
    base = np.median(seconds["serial"])
    for name, values in seconds.items():
        if not values:
            continue
        rates = [args.runs / s for s in values]
        print(f"| {name} | {np.median(rates):,.0f} ({min(rates):,.0f}-{max(rates):,.0f}) | "
              f"{base / np.median(values):.2f} |")
    if client is not None:                   # overhead per task: many tiny tasks of one 1-ms run each
        tiny = runs[:400]
        start = time.perf_counter()
        simulate_many(model, tiny, 1e-3, t_eval=[], client=client, chunk_size=1)
        dask_s = time.perf_counter() - start
        start = time.perf_counter()
        simulate_many(model, tiny, 1e-3, t_eval=[])
        serial_s = time.perf_counter() - start
        print(f"\nDask overhead per task: {(dask_s - serial_s / args.workers) / len(tiny) * 1e3:.2f} ms "
              f"({len(tiny)} tasks of one {1e-3} s run each; the default chunks hold "
              f"{max(1, args.runs // (4 * args.workers)):,} runs)")
        client.close()
        cluster.close()
    tracemalloc.start()
    study = simulate_many(model, [{"p": {restitution: 0.5}}] * args.memory_runs, 1e-3, t_eval=[])
    current, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    per_row, peak_row = current / args.memory_runs, peak / args.memory_runs
    print(f"memory of {args.memory_runs:,} summary rows: {current / 1e6:.1f} MB ({per_row:.0f} B per row, "
          f"{len(study.rows[0])} fields; peak {peak_row:.0f} B per row): 100,000 rows about {per_row * 1e5 / 1e6:.0f} MB "
          f"(peak {peak_row * 1e5 / 1e6:.0f} MB)")
    return 0
