"""Merges `modelgap bond bench --json` with the reference scripts' JSON lines and prints
the speed ratios (Python median / modelgap median) against the issue's bars, and the
relative differences of the final values as a cross-check of the results.

Run: python benches/reference/compare.py MODELGAP.json PYTHON.jsonl... [--note TEXT]
     [--out MERGED.json]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

#: (modelgap case, Python route, what is compared, the issue's bar or None).
PAIRS = [
    ("dc_motor_4s_1khz/auto", "dc_motor_4s_1khz/scipy_lsoda_numpy",
     "DC motor 0-4 s: modelgap auto vs scipy LSODA, numpy rhs", 100.0),
    ("dc_motor_4s_1khz/auto", "dc_motor_4s_1khz/scipy_lsoda_sympy",
     "DC motor 0-4 s: modelgap auto vs scipy LSODA, sympy rhs", None),
    ("dc_motor_4s_1khz/exact", "dc_motor_4s_1khz/scipy_lsoda_numpy",
     "DC motor 0-4 s: modelgap exact vs scipy LSODA, numpy rhs", None),
    ("dc_motor_4s_1khz/dopri5", "dc_motor_4s_1khz/scipy_lsoda_numpy",
     "DC motor 0-4 s: modelgap dopri5 vs scipy LSODA, numpy rhs", None),
    ("buck_motor_pwm_1s/auto", "buck_motor_pwm_1s/scipy_lsoda_segments",
     "PWM buck-motor 0-1 s: modelgap auto vs scipy LSODA, 2000 segments", None),
    ("buck_motor_pwm_1s/auto", "buck_motor_pwm_1s/bondgraphtools",
     "PWM buck-motor 0-1 s: modelgap auto vs BondGraphTools (IDA)", 400.0),
]


def read_python(paths: list[str]) -> dict[str, dict]:
    """The reference results, by name, from files of JSON lines."""
    results = {}
    for path in paths:
        for line in Path(path).read_text().splitlines():
            line = line.strip()
            if line.startswith("{"):
                record = json.loads(line)
                results[record["name"]] = record
    return results


def table(rows: list[list[str]], right: set[int]) -> str:
    """Rows as an aligned table; columns in `right` are right-aligned."""
    widths = [max(len(r[j]) for r in rows) for j in range(len(rows[0]))]
    lines = []
    for r in rows:
        cells = [c.rjust(w) if j in right else c.ljust(w)
                 for j, (c, w) in enumerate(zip(r, widths))]
        lines.append("  " + "  ".join(cells).rstrip())
    return "\n".join(lines)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("modelgap", help="output of `modelgap bond bench --json`")
    p.add_argument("python", nargs="+", help="JSON lines of the reference scripts")
    p.add_argument("--note", action="append", default=[],
                   help="a line to print under the table (e.g. why a route was skipped)")
    p.add_argument("--out", help="write everything merged to this JSON file")
    args = p.parse_args()

    mg = json.loads(Path(args.modelgap).read_text())
    ours = {c["name"]: c for c in mg["cases"]}
    theirs = read_python(args.python)

    rows = [["comparison", "python ms", "modelgap ms", "ratio", "bar", "verdict"]]
    ratios = []
    for case, route, label, bar in PAIRS:
        if case not in ours or route not in theirs:
            continue
        a, b = theirs[route]["median_ms"], ours[case]["median_ms"]
        ratio = a / b
        verdict = "" if bar is None else ("meets" if ratio >= bar else "MISSES")
        rows.append([label, f"{a:.3f}", f"{b:.4f}", f"{ratio:.0f}x",
                     "" if bar is None else f">= {bar:.0f}x", verdict])
        ratios.append({"modelgap": case, "python": route, "python_median_ms": a,
                       "modelgap_median_ms": b, "ratio": ratio, "bar": bar})
    cores = mg.get("machine", {}).get("cores", "?")
    print(f"\nmodelgap vs Python, side by side in one run ({cores} cores); "
          "ratio = Python median / modelgap median")
    print(table(rows, right={1, 2, 3, 4}))

    print("\nmodelgap cases:")
    mrows = [["case", "runs", "median ms", "min ms", "steps", "x real time"]]
    for c in mg["cases"]:
        mrows.append([c["name"], str(c["runs"]), f"{c['median_ms']:.4f}",
                      f"{c['min_ms']:.4f}", str(c["steps"]), f"{c['x_real_time']:.0f}"])
    print(table(mrows, right={1, 2, 3, 4, 5}))
    print("\nPython routes:")
    prow = [["route", "runs", "median ms", "min ms"]]
    for r in theirs.values():
        prow.append([r["name"], str(r["runs"]), f"{r['median_ms']:.3f}", f"{r['min_ms']:.3f}"])
    print(table(prow, right={1, 2, 3}))

    print("\ncross-check of final values (relative difference, modelgap vs Python):")
    crows = [["modelgap", "python", "variable", "modelgap", "python", "rel. diff"]]
    seen = set()
    for case, route, _, _ in PAIRS:
        if case not in ours or route not in theirs or route in seen:
            continue
        seen.add(route)
        for var, theirs_v in theirs[route]["final"].items():
            ours_v = ours[case]["final"].get(var)
            if ours_v is None:
                continue
            rel = abs(ours_v - theirs_v) / max(abs(ours_v), abs(theirs_v), 1e-300)
            crows.append([case, route.split("/")[-1], var, f"{ours_v:.9g}",
                          f"{theirs_v:.9g}", f"{rel:.1e}"])
    print(table(crows, right={3, 4, 5}))
    for c in mg.get("checks", []):
        if not c["ok"]:
            print(f"warning: modelgap check failed: {c['name']}: {c['value']} "
                  f"(expected {c['expected']})")
    for line in args.note:
        print(f"note: {line}")

    if args.out:
        merged = {"modelgap": mg, "python": list(theirs.values()), "ratios": ratios,
                  "notes": args.note}
        Path(args.out).write_text(json.dumps(merged, indent=2) + "\n")
        print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
