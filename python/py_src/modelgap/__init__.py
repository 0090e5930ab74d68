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
plots (matplotlib) in :mod:`modelgap.plot`. ``load_model`` loads either kind from a file or a
built-in name, and ``load_recording`` reads a recording the way the model takes it.
``explain_many`` explains many recordings, in threads or processes (every object it sends
pickles).

A model written in Python plugs into the same loop: any object with ``outputs`` (the
measured outputs it predicts), ``predict(recording, effects)`` (a dict of output name to
one value per sample, with each ``Effect`` applied at its values) and ``candidates()`` (the
``Candidate`` effects it could be missing), see :class:`ModelLike`.
"""

from __future__ import annotations

from concurrent.futures import Executor
from typing import (
    Any,
    Callable,
    Iterable,
    Mapping,
    Optional,
    Protocol,
    Sequence,
    TypeVar,
    Union,
    runtime_checkable,
)

import numpy.typing as npt

from ._modelgap import (
    Calibration,
    Candidate,
    Comparison,
    ConvergenceError,
    DataError,
    Effect,
    EffectParam,
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
    fit,
    load_model,
    load_recording,
    write_report,
)
from . import bond, cloth


@runtime_checkable
class ModelLike(Protocol):
    """A model written in Python, held against recordings like the built-in kinds.

    - ``outputs``: the names of the measured outputs it predicts (as in recordings);
    - ``predict(recording, effects)``: the outputs at the recording's times, driven by its
      inputs, as a dict of name to an array of one value per sample, with every ``Effect``
      of ``effects`` applied at its ``values`` (an effect's ``id`` says which of the
      model's ``candidates()`` it is);
    - ``candidates()``: the ``Candidate`` effects the model could be missing, each with its
      ``EffectParam`` parameters (bounds, start value, typical size).

    Optional: ``name`` (for reports), ``inputs`` (the recorded inputs it is driven by: the
    verdict holds what the model leaves against them) and ``unit(output)``. ``predict`` runs
    with the interpreter taken for that call only while the loop itself runs in parallel;
    it may raise ``modelgap.ModelError`` for values it cannot simulate (the fit steps away),
    and any other exception stops the loop and comes back as itself.
    """

    @property
    def outputs(self) -> Sequence[str]:
        """The names of the measured outputs the model predicts (as in recordings)."""
        ...

    def predict(
        self, recording: Recording, effects: Sequence[Effect]
    ) -> Mapping[str, npt.ArrayLike]:
        """The outputs at ``recording``'s times, driven by its inputs, with every
        ``Effect`` of ``effects`` applied at its ``values``: a dict of output name to an
        array of one value per sample. Raise ``modelgap.ModelError`` for values the model
        cannot simulate."""
        ...

    def candidates(self) -> Sequence[Candidate]:
        """The ``Candidate`` effects the model could be missing."""
        ...


Model = Union[bond.BondModel, cloth.ClothModel, ModelLike]
"""What ``compare``, ``explain`` and ``fix`` take: a bond-graph model, a cloth model or a model
written in Python (:class:`ModelLike`)."""


class WithEffects:
    """A model written in Python with effects built in: it predicts with them applied before
    any the loop adds (what ``with_effects`` gives for a model that has no ``with_effects``
    of its own)."""

    def __init__(self, model: ModelLike, effects: Sequence[Effect]) -> None:
        self.model = model
        self.effects = list(effects)
        self.name = getattr(model, "name", type(model).__name__)

    @property
    def outputs(self) -> Sequence[str]:
        """The wrapped model's outputs."""
        return self.model.outputs

    @property
    def inputs(self) -> Sequence[str]:
        """The wrapped model's inputs (empty when it names none)."""
        return list(getattr(self.model, "inputs", []))

    def unit(self, output: str) -> str:
        """The unit of ``output`` as the wrapped model gives it (``""`` when it gives none)."""
        unit = getattr(self.model, "unit", None)
        return unit(output) if unit is not None else ""

    def predict(
        self, recording: Recording, effects: Sequence[Effect]
    ) -> Mapping[str, npt.ArrayLike]:
        """The wrapped model's prediction with the built-in effects, then ``effects``."""
        return self.model.predict(recording, [*self.effects, *effects])

    def candidates(self) -> Sequence[Candidate]:
        """The wrapped model's candidates."""
        return self.model.candidates()

    def __repr__(self) -> str:
        ids = ", ".join(e.id for e in self.effects)
        return f"<WithEffects {self.name} + [{ids}]>"


_M = TypeVar("_M")


def with_effects(model: _M, effects: Sequence[Effect]) -> _M:
    """The model with ``effects`` built in: the model's own ``with_effects`` (``BondModel``,
    ``ClothModel``, or a Python model that has one), else a :class:`WithEffects` around it."""
    own = getattr(model, "with_effects", None)
    if own is not None:
        return own(list(effects))  # type: ignore[no-any-return]
    return WithEffects(model, effects)  # type: ignore[arg-type, return-value]

__all__ = [
    "Calibration",
    "Candidate",
    "Comparison",
    "ConvergenceError",
    "DataError",
    "Effect",
    "EffectParam",
    "Explanation",
    "FittedParam",
    "Model",
    "ModelError",
    "ModelLike",
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
    "fit",
    "fix",
    "load_model",
    "load_recording",
    "with_effects",
    "WithEffects",
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
    """Explains ``rec`` and returns the model with the chosen effects built in
    (:func:`with_effects`).

    When nothing is missing the model comes back unchanged (a new, equal model).

    Args:
        model: A ``BondModel``, a ``ClothModel`` or a model written in Python
            (:class:`ModelLike`).
        rec: The recording: the model's inputs and measured outputs.
        noise: Known noise floors, output name to σ in the output's unit (as ``explain``).
        significance: The score the best candidate must beat (as ``explain``).
        max_effects: 2 lets a second effect be chosen, 1 at most one (as ``explain``).
        progress: Called as ``progress(done, total)`` with the candidate fits finished (as
            ``explain``).

    Returns:
        A new model of the same kind with ``explain``'s chosen effects built in (a
        :class:`WithEffects` for a Python model without ``with_effects``).

    Raises:
        DataError: As ``explain``, for bad options or a recording that does not fit.
        ModelError: When the model cannot be simulated.
        ConvergenceError: When a bond-graph simulation fails.
        KeyboardInterrupt: On Ctrl-C.
    """
    ex = explain(
        model,
        rec,
        noise=dict(noise) if noise is not None else None,
        significance=significance,
        max_effects=max_effects,
        progress=progress,
    )
    return with_effects(model, ex.effects)


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
