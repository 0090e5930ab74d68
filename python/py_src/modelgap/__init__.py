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

Bond-graph models live in :mod:`modelgap.bond`, the cloth simulator in :mod:`modelgap.cloth`,
plots (matplotlib) in :mod:`modelgap.plot`. ``explain_many`` explains many recordings, in
threads or processes (every object it sends pickles).
"""

from __future__ import annotations

from concurrent.futures import Executor
from typing import Any, Callable, Iterable, Mapping, Optional, Sequence, TypeVar, Union

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
from . import bond, cloth

Model = Union[bond.BondModel, cloth.ClothModel]
"""What ``compare``, ``explain`` and ``fix`` take: a bond-graph model or a cloth model."""

_M = TypeVar("_M", bond.BondModel, cloth.ClothModel)

__all__ = [
    "Comparison",
    "ConvergenceError",
    "DataError",
    "Effect",
    "Explanation",
    "FittedParam",
    "Model",
    "ModelError",
    "ModelgapError",
    "OutputComparison",
    "OutputSummary",
    "RankedCandidate",
    "Recording",
    "bond",
    "cloth",
    "compare",
    "explain",
    "explain_many",
    "fix",
    "write_report",
]


def fix(
    model: _M,
    rec: Recording,
    *,
    noise: Optional[Mapping[str, float]] = None,
    significance: float = 10.0,
    max_effects: int = 2,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> _M:
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


def _explain_one(model: Any, rec: Recording, options: dict[str, Any]) -> Explanation:
    """``explain`` with its options as a dict: what ``explain_many`` sends to a worker (a
    module-level function, so that a process pool can pickle it)."""
    return explain(model, rec, **options)


def explain_many(
    model: Model,
    recordings: Iterable[Recording],
    executor: Optional[Executor] = None,
    **options: Any,
) -> list[Explanation]:
    """Explains each recording with the same model; the explanations come back in order.

    With an ``executor`` (any ``concurrent.futures.Executor``) the recordings are explained
    concurrently. ``explain`` releases the GIL, so a ``ThreadPoolExecutor`` runs them in
    parallel; a ``ProcessPoolExecutor`` (best with the ``"spawn"`` or ``"forkserver"``
    start method) works too, since the model, the recordings and the explanations pickle,
    and so do executors of Dask or Ray that follow the same interface. Without one they run
    one after the other. ``options`` go to ``explain`` (a ``progress`` callback must be
    picklable for a process pool).
    """
    recs: Sequence[Recording] = list(recordings)
    if executor is None:
        return [explain(model, r, **options) for r in recs]
    futures = [executor.submit(_explain_one, model, r, dict(options)) for r in recs]
    return [f.result() for f in futures]
