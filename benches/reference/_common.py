"""Shared by the reference scripts: model parameters from the model files, and timing."""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
import tomllib
from pathlib import Path
from typing import Any, Callable

#: The repository's root (this file is benches/reference/_common.py).
ROOT = Path(__file__).resolve().parents[2]
#: The model files the Rust library ships (crates/modelgap-bond/models/*.toml).
MODELS = ROOT / "crates" / "modelgap-bond" / "models"


def model_values(name: str) -> tuple[dict[str, float], dict[str, float]]:
    """The parameter values and input defaults of a model file, by name."""
    with open(MODELS / f"{name}.toml", "rb") as f:
        model = tomllib.load(f)
    params = {k: float(v["value"]) for k, v in model["parameters"].items()}
    inputs = {k: float(v["default"]) for k, v in model["inputs"].items()}
    return params, inputs


def arguments(description: str) -> argparse.Namespace:
    """Command-line options every reference script takes."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--repeat", type=int, default=None,
                   help="timed runs per route (default: enough for --min-time, at least 5)")
    p.add_argument("--min-time", type=float, default=2.0,
                   help="seconds of timed runs per route when --repeat is not given")
    return p.parse_args()


def time_runs(run: Callable[[], Any], repeat: int | None, min_time: float,
              max_runs: int = 500) -> tuple[list[float], Any]:
    """Times `run` timeit-style: one warm-up call, then `repeat` timed calls (or as many
    as fill `min_time` seconds, at least 5, at most `max_runs`). Returns the wall times in
    ms and the warm-up call's result."""
    t0 = time.perf_counter()
    result = run()
    once = time.perf_counter() - t0
    if repeat is None:
        repeat = max(5, min(max_runs, int(min_time / max(once, 1e-9)) + 1))
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        run()
        times.append((time.perf_counter() - t0) * 1e3)
    return times, result


def emit(name: str, times_ms: list[float], final: dict[str, float], **extra: Any) -> None:
    """Prints one result as a JSON line: name, median_ms, min_ms, runs, final, extras."""
    record = {
        "name": name,
        "median_ms": statistics.median(times_ms),
        "min_ms": min(times_ms),
        "runs": len(times_ms),
        "final": final,
    }
    record.update(extra)
    print(json.dumps(record), flush=True)


def note(text: str) -> None:
    """A line for people, on standard error (standard output carries the JSON)."""
    print(text, file=sys.stderr, flush=True)
