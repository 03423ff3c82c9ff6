"""python -m studies stress [--only NAME ...] [--quick] [--list] [--json [FILE]]: the stress suite (the cases
``studies.stress_cases.CASES``, run and checked by the engine ``studies.stress``), as a table, with exit code 1 if
any case fails."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from . import stress_cases
from .stress import format_table, run_case, tolerances_line


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m studies stress",
        description="Run the stiff and extreme scenes of the stress suite; each must show no NaN, no "
                    "penetration, no energy gain and the expected status/message. Exit code 1 if any fails.")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="run only these cases")
    parser.add_argument("--quick", action="store_true", help="leave out the slow cases (n = 32, ...)")
    parser.add_argument("--list", action="store_true", help="list the cases and stop")
    parser.add_argument("--json", nargs="?", const="-", metavar="FILE",
                        help="write the rows as JSON to FILE (or to stdout instead of the table)")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    cases = list(stress_cases.CASES)
    names = [c.name for c in cases]
    if args.only:
        unknown = [name for name in args.only if name not in names]
        if unknown:
            print(f"error: --only: unknown case(s) {', '.join(unknown)}; cases: {', '.join(names)}",
                  file=sys.stderr)
            return 2
        cases = [c for c in cases if c.name in args.only]
    elif args.quick:
        cases = [c for c in cases if not c.slow]
    if args.json and args.json != "-":
        from codegen.outputs import output_file_problem
        problem = output_file_problem("--json", args.json)
        if problem:
            print(f"error: {problem}", file=sys.stderr)
            return 2
    if args.list:
        for c in stress_cases.CASES:
            print(f"{c.name:28s} {'slow  ' if c.slow else '      '}{c.description}")
        return 0
    outcomes = []
    for k, case in enumerate(cases, start=1):
        print(f"[{k}/{len(cases)}] {case.name} ...", file=sys.stderr, flush=True)
        outcome = run_case(case, progress=lambda m: print(f"    {m}", file=sys.stderr, flush=True))
        r = outcome.row
        print(f"[{k}/{len(cases)}] {case.name}: {r['result']} ({r['seconds']:.2f} s)"
              + ("" if outcome.passed else " -- " + "; ".join(outcome.reasons)), file=sys.stderr, flush=True)
        outcomes.append(outcome)
    failed = sum(not o.passed for o in outcomes)
    if args.json:
        text = json.dumps([{**o.row, "description": o.case.description, "expect": o.case.expect.describe()}
                           for o in outcomes], indent=1, default=float)
        if args.json == "-":
            print(text)
        else:
            Path(args.json).write_text(text)
    if args.json != "-":
        print(tolerances_line())
        print(format_table(outcomes))
        print(f"{len(outcomes) - failed} passed, {failed} failed")
        if args.json:
            print(f"wrote {args.json}")
    return 1 if failed else 0



if __name__ == "__main__":
    sys.exit(main())
