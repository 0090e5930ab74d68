"""modelgap: hold physical models against measurements and find the missing effect.

The measurement loop::

    import modelgap
    from modelgap.bond import BondModel

    motor = BondModel.dc_motor()
    rec = modelgap.Recording.load("run.csv")
    before = modelgap.compare(motor, rec)          # where the model fails
    ex = modelgap.explain(motor, rec)              # which effect is missing
    fixed = motor.with_effects(ex.effects)         # add it ...
    after = modelgap.compare(fixed, rec)           # ... and watch the error fall

Bond-graph models live in :mod:`modelgap.bond`; plots (matplotlib) in :mod:`modelgap.plot`.
"""

from __future__ import annotations

from concurrent.futures import Executor
from typing import Any, Callable, Iterable, Mapping, Optional, Sequence

from ._modelgap import (
    Comparison,
    ConvergenceError,
    DataError,
    Effect,
    Explanation,
    FittedParam,
    ModelError,
    ModelgapError,
    OutputComparison,
    OutputSummary,
    RankedCandidate,
    Recording,
    compare,
    explain,
    write_report,
)
from . import bond

__all__ = [
    "Comparison",
    "ConvergenceError",
    "DataError",
    "Effect",
    "Explanation",
    "FittedParam",
    "ModelError",
    "ModelgapError",
    "OutputComparison",
    "OutputSummary",
    "RankedCandidate",
    "Recording",
    "bond",
    "compare",
    "explain",
    "explain_many",
    "fix",
    "write_report",
]


def fix(
    model: bond.BondModel,
    rec: Recording,
    *,
    noise: Optional[Mapping[str, float]] = None,
    significance: float = 10.0,
    max_effects: int = 2,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> bond.BondModel:
    """Explains ``rec`` and returns the model with the chosen effects built in.

    When nothing is missing the model comes back unchanged (a new, equal model).
    """
    ex = explain(
        model,
        rec,
        noise=dict(noise) if noise is not None else None,
        significance=significance,
        max_effects=max_effects,
        progress=progress,
    )
    return model.with_effects(ex.effects)


def explain_many(
    model: bond.BondModel,
    recordings: Iterable[Recording],
    executor: Optional[Executor] = None,
    **options: Any,
) -> list[Explanation]:
    """Explains each recording with the same model, in order.

    With an ``executor`` (a ``concurrent.futures`` executor) the recordings are explained
    concurrently; ``explain`` releases the GIL, so a ``ThreadPoolExecutor`` runs them in
    parallel. Without one they run one after the other. ``options`` go to ``explain``.
    """
    recs: Sequence[Recording] = list(recordings)
    if executor is None:
        return [explain(model, r, **options) for r in recs]
    futures = [executor.submit(explain, model, r, **options) for r in recs]
    return [f.result() for f in futures]
