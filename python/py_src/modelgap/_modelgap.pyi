# Hand-written stubs of the extension module; checked by `python -m mypy.stubtest modelgap._modelgap`.
"""The compiled core of modelgap (re-exported by ``modelgap``, ``modelgap.bond`` and
``modelgap.cloth``).

Units are SI throughout: time in s, lengths in m, masses in kg, forces in N, voltages in V,
currents in A, angular velocities in rad/s; a recorded signal or a model output carries the
unit of its model (``OutputComparison.unit``, ``BondModel.units``).

Errors are ``ModelgapError`` subclasses with the Rust message unchanged: ``DataError`` (also
a ``ValueError``) for bad recordings, files and arguments, ``ModelError`` for a model that
cannot be built, derived or simulated, ``ConvergenceError`` for a fit, a steady state or an
ODE solve that does not converge. A run stopped by Ctrl-C raises ``KeyboardInterrupt``; an
object that is not a model raises ``TypeError``.
"""

from os import PathLike
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Protocol, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "BondModel",
    "Calibration",
    "Candidate",
    "ClothMesh",
    "ClothModel",
    "ClothRun",
    "ClothWorld",
    "Collider",
    "Comparison",
    "ConvergenceError",
    "DataError",
    "Diagnosis",
    "Effect",
    "EffectParam",
    "Explanation",
    "FittedParam",
    "MarkerRecording",
    "ModelError",
    "ModelgapError",
    "OutputComparison",
    "OutputSummary",
    "RankedCandidate",
    "Recording",
    "Scene",
    "SolverParams",
    "StepReport",
    "compare",
    "explain",
    "fit",
    "hidden_cases",
    "hidden_recording",
    "load_model",
    "load_recording",
    "scene",
    "scenes",
    "table7",
    "write_report",
]

_Path = Union[str, PathLike[str]]
_F64 = npt.NDArray[np.float64]
_Window = tuple[float, float, float]

class ModelgapError(Exception):
    """Base class of every error modelgap raises.

    Raised as itself only for an internal error (a bug in modelgap, a panic in Rust); the
    errors of inputs and models are its subclasses ``DataError``, ``ModelError`` and
    ``ConvergenceError``. A run stopped by Ctrl-C raises ``KeyboardInterrupt`` instead.
    """

class DataError(ModelgapError, ValueError):
    """Bad input data: a recording, a file, an argument. Also a ``ValueError``.

    Raised for files that cannot be read or parsed (naming the line and column), recordings
    that break an invariant (time not strictly increasing, non-finite values, wrong shapes),
    unknown names (signals, inputs, parameters, built-in models, scenes) and option values
    out of range (a noise floor that is not positive, an unknown ``hold`` or ``method``).
    """

class ModelError(ModelgapError):
    """A model cannot be built, derived or simulated.

    For example a causal conflict or algebraic loop in a bond graph, a law that is not finite,
    a state that runs away, a cloth simulation that diverges, or effect values a model cannot
    take. A model written in Python raises it from ``predict`` to say it cannot simulate at
    the values asked for: a fit then steps away from them.
    """

class ConvergenceError(ModelgapError):
    """A fit, a steady-state solve or an ODE solve did not converge.

    Raised when a bond-graph model has no steady state to start from (``steady_state``,
    ``steady_start=True``), when its ODE solver fails, or when a fit cannot run at all.
    """

@final
class Recording:
    """Sampled signals on one strictly increasing time axis (s), checked when built or read.

    Build one with ``Recording(t, values, names)`` (``values`` shaped
    ``(n_samples, n_signals)``), ``Recording.from_numpy`` (the same) or
    ``Recording.load(path)`` (``.csv`` or ``.mcap``). Every array read from it is a fresh
    float64 copy. Recordings compare equal by value and pickle.
    """

    def __new__(cls, t: npt.ArrayLike, values: npt.ArrayLike, names: list[str]) -> Recording:
        """Builds a recording from numpy arrays (as ``Recording.from_numpy``).

        Args:
            t: Sample times (s), shape ``(n_samples,)``, finite and strictly increasing.
            values: Signal values in SI units, shape ``(n_samples, n_signals)``, one column
                per name (a 1-D array when there is one name).
            names: One name per column: non-empty, unique, not ``"t"``.

        Raises:
            DataError: For an empty time axis, a bad shape, a non-finite or too large value,
                time that does not strictly increase, or a bad or duplicate name.
        """

    @staticmethod
    def from_numpy(t: npt.ArrayLike, values: npt.ArrayLike, names: list[str]) -> Recording:
        """A recording from numpy arrays.

        Args:
            t: Sample times (s), shape ``(n_samples,)``, finite and strictly increasing.
            values: Signal values in SI units, shape ``(n_samples, n_signals)``, one column
                per name (a 1-D array when there is one name).
            names: One name per column: non-empty, unique, not ``"t"``.

        Returns:
            The recording (its arrays copied).

        Raises:
            DataError: For an empty time axis, a bad shape, a non-finite or too large value,
                time that does not strictly increase, or a bad or duplicate name.
        """

    @staticmethod
    def load(
        path: _Path,
        *,
        time: Optional[str] = None,
        delimiter: Optional[str] = None,
        decimal_comma: Optional[bool] = None,
    ) -> Recording:
        """Reads a recording from a ``.csv`` file, the ``/signals`` topic of an ``.mcap`` file,
        or a ``.parquet`` (``.pq``) file.

        A CSV file has a header naming the columns and one row per sample; lines starting with
        ``#`` are comments. Files as pandas, R or a spreadsheet export them read as they are:
        quoted cells; a first column of row numbers (pandas' unnamed index, R's row names) is
        left out; the time column is ``t``, else the one named ``t`` with a unit, else the one
        named ``t`` or ``time`` in any case, anywhere in the header, with or without a unit
        (``time [ms]`` is converted to seconds; of several, one whose unit is no time unit,
        such as ``T [degC]``, is not time); ``;`` or tabs between cells are detected, and with them decimal commas
        (``1,5``); ``name [unit]`` headers and a unit row under the header give units.

        A Parquet file reads as pandas (``df.to_parquet()``, Snappy) and Polars
        (``df.write_parquet()``, zstd) write it, over any number of row groups: its columns
        mean what CSV columns do (time found by name, ``name [unit]``, the pandas index left
        out); numbers of any width, timestamps (seconds from the first sample) and pandas'
        timedeltas (seconds) are read; nulls, NaN, text columns and other codecs are refused,
        naming the column and the row (counted from 0). The GIL is released while reading.

        Args:
            path: The file; its extension (``.csv``, ``.mcap``, ``.parquet`` or ``.pq``)
                chooses the format.
            time: CSV and Parquet: the time column, named as in the header, with or without
                its unit.
            delimiter: CSV: the one character between cells (``";"``, ``"\\t"``) instead of
                detecting it.
            decimal_comma: CSV: whether numbers are written ``1,5``; needed for quoted
                decimal commas between ``,`` cells, detected with ``;`` or tabs.

        Returns:
            The recording.

        Raises:
            DataError: For a file that cannot be read (truncated or corrupt), an unknown
                extension, bad content (naming the line and column, the MCAP message, or the
                Parquet row and column), a time column that is missing (the message lists the
                columns) or ambiguous, or CSV options with an ``.mcap`` or ``.parquet`` file
                (``time`` excepted for Parquet).
        """

    def save(self, path: _Path) -> None:
        """Writes the recording as ``.csv`` or (zstd) ``.mcap``, chosen by the extension.

        CSV values are written so that reading them back gives an identical recording. The
        GIL is released while writing. Parquet is read, not written.

        Args:
            path: The file to write.

        Raises:
            DataError: For an unknown extension or ``.parquet`` (nothing is written) or a
                write that fails.
        """

    def to_numpy(self) -> tuple[_F64, _F64, list[str]]:
        """The recording as numpy arrays.

        Returns:
            ``(t, values, names)``: times (s) shaped ``(n_samples,)``, values shaped
            ``(n_samples, n_signals)`` and the signal names, fresh float64 copies.
        """

    @property
    def t(self) -> _F64:
        """The time axis (s), a fresh float64 array of shape ``(n_samples,)``."""

    @property
    def names(self) -> list[str]:
        """The signal names, in column order (the time column ``t`` not included)."""

    @property
    def duration(self) -> float:
        """The time from the first to the last sample (s)."""

    def signal(self, name: str) -> _F64:
        """The values of one signal.

        Args:
            name: The signal's name.

        Returns:
            A fresh float64 array of shape ``(n_samples,)``.

        Raises:
            DataError: When there is no such signal (naming the available ones).
        """

    def __len__(self) -> int:
        """The number of samples."""

    def __contains__(self, key: str, /) -> bool:
        """Whether the recording has a signal named ``key``."""

    def __eq__(self, value: object, /) -> bool: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...

@final
class OutputComparison:
    """One measured output held against the model's prediction (an item of
    ``Comparison.outputs``)."""

    @property
    def name(self) -> str:
        """The output's name (as in the recording)."""

    @property
    def unit(self) -> str:
        """The output's unit, as the model gives it (empty when unknown)."""

    @property
    def rms(self) -> float:
        """The root mean square of the residual (measured − predicted), in the output's unit."""

    @property
    def nrms(self) -> float:
        """``rms`` over the RMS of the measurement (dimensionless; 0 or inf for a zero
        measurement)."""

    @property
    def max_abs(self) -> float:
        """The largest absolute residual, in the output's unit."""

    @property
    def mean(self) -> float:
        """The mean residual (the bias), in the output's unit."""

    @property
    def noise_floor(self) -> float:
        """The noise floor σ, in the output's unit: the RMS a perfect model would leave.

        Given through ``noise=``, else estimated from the measurement's high-frequency part
        (with its quantisation step added in quadrature).
        """

    @property
    def noise_given(self) -> bool:
        """True when the noise floor was given (``noise=``), false when estimated."""

    @property
    def noise_method(self) -> str:
        """How the noise floor was found and how far to trust it: ``"given"``, ``"white"``
        (third differences that are white noise), ``"quantised"``, ``"coloured"`` (correlated
        noise or a filtered signal: likely too low), ``"signal-content"`` (the signal's own
        fast content: likely too high) or ``"unchecked"``; ``explain`` may also give
        ``"smoother"`` (see ``OutputSummary.noise_method``)."""

    @property
    def rms_over_floor(self) -> float:
        """``rms`` over ``noise_floor``: about 1 for a right model."""

    @property
    def band(self) -> float:
        """The half-width of the band the residual must leave to count as failure, in the
        output's unit.

        ``band_sigmas`` × the noise floor, or ``band_fraction`` × the prediction's steady
        state; with a predictability band (cloth), that band adds to it sample by sample.
        """

    @property
    def windows(self) -> list[_Window]:
        """Where the residual leaves its band: ``(start, end, peak)`` tuples, start and end
        in s, peak the largest absolute residual in the window (output's unit)."""

    @property
    def effective_samples(self) -> float:
        """The effective number of independent samples of the residual."""

    @property
    def quantum(self) -> Optional[float]:
        """The measurement's quantisation step (output's unit) when it lies on a lattice (its
        rounding error is part of the floor), else ``None``."""

    @property
    def finding(self) -> Optional[str]:
        """Why this output cannot be judged (a dead sensor that reads a constant), else
        ``None``."""

    @property
    def residual(self) -> _F64:
        """measured − predicted per sample (output's unit), a fresh float64 array."""

    @property
    def predicted(self) -> _F64:
        """The model's prediction per sample (output's unit), a fresh float64 array."""

    @property
    def measured(self) -> _F64:
        """The measurement per sample (output's unit), a fresh float64 array."""

@final
class Comparison:
    """The result of ``compare``: per output, residual statistics, noise floor and the windows
    where the model fails. Comparisons compare equal by value and pickle."""

    @property
    def model(self) -> str:
        """The model's name."""

    @property
    def t(self) -> _F64:
        """The sample times (s), a fresh float64 array."""

    @property
    def outputs(self) -> list[OutputComparison]:
        """One ``OutputComparison`` per output the model predicts and the recording measures,
        in the model's order."""

    @property
    def warnings(self) -> list[str]:
        """What keeps the recording, or an output of it, from being judged: too few samples, a
        dead sensor, a time base that hides the model's time constants."""

    def output(self, name: str) -> OutputComparison:
        """The comparison of one output.

        Args:
            name: The output's name.

        Returns:
            Its ``OutputComparison``.

        Raises:
            DataError: For an output not compared (naming those that were).
        """

    def text(self) -> str:
        """Where the model fails, output by output, as text (what the command line prints).

        Returns:
            The text, several lines.
        """

    @staticmethod
    def _from_state(state: str) -> Comparison: ...
    def __reduce__(self) -> tuple[Any, tuple[str]]: ...
    def __eq__(self, value: object, /) -> bool: ...

@final
class Effect:
    """A candidate effect with parameter values, ready for ``model.with_effects``.

    Found in ``Explanation.effects`` and ``RankedCandidate.effect``, made by
    ``Candidate.effect``, passed to a Python model's ``predict``. Effects compare equal by
    value and pickle (as JSON).
    """

    @property
    def id(self) -> str:
        """The candidate's stable id (``coulomb@1m``, ``deviation:R``, ``air-drag``)."""

    @property
    def name(self) -> str:
        """The candidate's plain name."""

    @property
    def kind(self) -> str:
        """``"parameter-deviation"``, ``"abrupt-change"`` or ``"missing-element"``."""

    @property
    def acts_on(self) -> str:
        """Where it acts (an element, a parameter, ``cloth``)."""

    @property
    def values(self) -> dict[str, float]:
        """The parameter values by name, each in its parameter's unit; a fresh dict."""

    def to_json(self) -> str:
        """The effect as JSON (what pickling stores).

        Returns:
            The JSON text: the candidate and the values.
        """

    @staticmethod
    def from_json(text: str) -> Effect:
        """An effect from the JSON of ``to_json``.

        Args:
            text: The JSON text.

        Returns:
            The effect.

        Raises:
            DataError: When the text is not the JSON of an effect.
        """

    def __eq__(self, value: object, /) -> bool: ...
    def __reduce__(self) -> tuple[Any, tuple[str]]: ...

@final
class FittedParam:
    """One fitted parameter of a candidate (an item of ``RankedCandidate.params``)."""

    @property
    def name(self) -> str:
        """The parameter's name."""

    @property
    def unit(self) -> str:
        """The parameter's unit."""

    @property
    def value(self) -> float:
        """The fitted value, in ``unit``."""

    @property
    def std_error(self) -> float:
        """The standard error of ``value`` (in ``unit``): the fit's sandwich over its residual,
        and for a chosen effect no smaller than half the difference of its fits on the
        recording's two halves; infinite when the parameter sits at a bound or the fit
        failed."""

    @property
    def at_bound(self) -> Optional[str]:
        """``"lower"`` or ``"upper"`` when the fit ended on that bound (the value is a limit
        the fit ran into, not an estimate, and has no standard error), else ``None``."""

@final
class RankedCandidate:
    """A candidate effect after its fit, with its evidence (an item of
    ``Explanation.ranked`` and ``Explanation.chosen``)."""

    @property
    def id(self) -> str:
        """The candidate's stable id."""

    @property
    def name(self) -> str:
        """The candidate's plain name."""

    @property
    def kind(self) -> str:
        """``"parameter-deviation"``, ``"abrupt-change"`` or ``"missing-element"``."""

    @property
    def acts_on(self) -> str:
        """Where it acts (an element, a parameter, ``cloth``)."""

    @property
    def params(self) -> list[FittedParam]:
        """The fitted parameters, in the candidate's order."""

    @property
    def rms_after(self) -> list[float]:
        """The RMS per output with the effect added (each in its output's unit), in the order
        of ``Explanation.outputs``; empty when the fit failed before any residual."""

    @property
    def score(self) -> float:
        """The evidence for the effect, a BIC difference: ``n_eff · ln(cost_before / cost) −
        k · ln(n_eff)`` with k parameters; higher is better, ``-inf`` when the fit failed.

        For the second of two chosen effects it is the gain over the first alone.
        """

    @property
    def cost(self) -> float:
        """The weighted cost after the fit, ``½ Σ (residual / σ)²`` (dimensionless)."""

    @property
    def termination(self) -> str:
        """How the fit ended: ``"converged"``, ``"max-iterations"``, ``"stalled"`` or
        ``"cancelled"``."""

    @property
    def qualitative(self) -> Optional[bool]:
        """Whether the model's qualitative diagnosis (fault trees, signatures) agrees with the
        effect; ``None`` when it has no opinion or was not asked (only the top five are)."""

    @property
    def qualitative_reason(self) -> str:
        """Why the qualitative diagnosis agrees or disagrees, in plain words (which outputs
        deviated first, what their fault trees point at, how this effect would show); ``""``
        when it gives no reason."""

    @property
    def indistinct(self) -> list[str]:
        """Plain names of other physics this recording cannot tell from this effect: as many
        parameters, both significant, scores within the significance margin."""

    @property
    def error(self) -> Optional[str]:
        """Why the fit failed, if it did (the candidate then ranks last), else ``None``."""

    @property
    def equivalent(self) -> list[str]:
        """The ids of candidates with as many parameters that explain the recording exactly as
        well: the same physics said another way."""

    @property
    def effect(self) -> Effect:
        """The fitted effect, ready for ``model.with_effects``."""

@final
class OutputSummary:
    """One output before and after the chosen effects (an item of ``Explanation.outputs``)."""

    @property
    def name(self) -> str:
        """The output's name."""

    @property
    def unit(self) -> str:
        """The output's unit."""

    @property
    def noise_floor(self) -> float:
        """The noise floor σ, in the output's unit (given through ``noise=`` or estimated)."""

    @property
    def noise_method(self) -> str:
        """How the noise floor was found: as ``Output.noise_method``, or ``"smoother"``: the
        white noise the model leaves with a free effort at the place that explains most (taken
        where the third differences carry the signal)."""

    @property
    def rms_before(self) -> float:
        """The residual's RMS with the model as given, in the output's unit."""

    @property
    def rms_after(self) -> float:
        """The residual's RMS with the chosen effects, in the output's unit (equal to
        ``rms_before`` when none is chosen)."""

    @property
    def remaining_windows(self) -> list[_Window]:
        """Where the residual after the effects still leaves a 4σ band: ``(start, end, peak)``
        tuples (s, s, output's unit)."""

    @property
    def at_floor(self) -> Optional[bool]:
        """Whether the residual after the effects is what noise leaves: at its floor (or taken
        for coloured noise), no failure window, uncorrelated with the inputs, unbiased;
        ``None`` when the recording could not be judged."""

    @property
    def noise_sigma(self) -> Optional[float]:
        """σ of the noise the residual was taken for (the floor, or the level of coloured
        noise), in the output's unit; ``None`` when not judged."""

    @property
    def noise_rho(self) -> Optional[float]:
        """The AR(1) coefficient of the noise model the scores whiten this output's residual
        with; at its cap of 0.999 the residual is mostly model error, and the scores weigh its
        changes from sample to sample. ``None`` when nothing was scored."""

    @property
    def reasons(self) -> list[str]:
        """Why the residual is not what noise leaves (empty when it is, or when not judged)."""

@final
class Explanation:
    """The result of ``explain``: the verdict, the ranked candidates and the chosen effects.

    Explanations compare equal by value and pickle.
    """

    @property
    def model(self) -> str:
        """The model's name."""

    @property
    def verdict(self) -> str:
        """The answer, one of:

        - ``"nothing-missing"``: every output's residual is what noise leaves;
        - ``"effect-found"``: one effect explains the recording down to the noise floor;
        - ``"two-effects"``: two effects together do;
        - ``"partial"``: the chosen effects help but leave a residual above the floor;
        - ``"unexplained"``: the model fails and no candidate explains any of it
          significantly (or there is no candidate to try);
        - ``"cannot-judge"``: the recording cannot be judged (too few samples, no output
          that moves, a time base that hides the model's dynamics, every fit failing);
        - ``"interrupted"``: the run was stopped before a verdict (``explain`` called from
          Python raises ``KeyboardInterrupt`` or the stopping exception instead of
          returning it).
        """

    @property
    def outputs(self) -> list[OutputSummary]:
        """Per output judged: noise floor, RMS before and after the chosen effects."""

    @property
    def ranked(self) -> list[RankedCandidate]:
        """Every candidate fitted, best first (failed fits last)."""

    @property
    def chosen(self) -> list[RankedCandidate]:
        """The chosen candidates: none, one or two."""

    @property
    def effects(self) -> list[Effect]:
        """The chosen effects with their fitted values, ready for ``model.with_effects``."""

    @property
    def margin(self) -> float:
        """The score of the best candidate minus that of the runner-up (the best's own score
        when there is no finite runner-up, 0 with no candidate)."""

    @property
    def effective_samples(self) -> float:
        """The effective number of independent samples the scores use."""

    @property
    def warnings(self) -> list[str]:
        """Non-fatal findings: outputs left out of the verdict, candidate fits that failed."""

    @property
    def reasons(self) -> list[str]:
        """Why the verdict is what it is when it is not a complete answer: what keeps the
        recording from being judged, which output's residual is not noise and how, or how
        far an interrupted run got."""

    @property
    def places(self) -> list[dict[str, Any]]:
        """Where the model fails: each place discovery looked at (a junction of a bond
        graph), most explaining first, as a dict with ``location``, ``place``, ``quantity``
        (``'effort'`` or ``'flow'``), ``unit``, ``explained`` (the share of the outputs' error
        an effort there removes, 0–1), ``rms`` and ``band`` of the missing effort, and
        ``law`` (``None``, or the law the screen found: ``formula``, ``text``,
        ``explained``, ``terms``)."""

    def missing(
        self, location: str
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """The missing effort (or flow) estimated at a place, to plot or export.

        Args:
            location: The place's element name (``'1m'``), as in :attr:`places`.

        Returns:
            ``(t, value, band)``: times (s), the estimate and its one-sigma band (the
            place's unit).

        Raises:
            DataError: No estimate at that place (it names the places there are). An
                explanation restored from a pickle keeps no series.
        """

    @property
    def timings(self) -> list[tuple[str, float, float | None]]:
        """How long each stage took, in the order run: ``(stage, wall_s, cpu_s)`` with stage
        one of ``"calibrate"``, ``"estimate"``, ``"screen"``, ``"screen-menu"``, ``"confirm"``,
        ``"pairs"``, ``"judge"``; times in seconds, ``cpu_s`` the whole process's CPU time over
        the stage (every thread; ``None`` where the platform does not say). Not part of
        equality."""

    def text(self, top: int = 5) -> str:
        """The ranking and the verdict as text (what the command line prints).

        Args:
            top: How many of the best candidates to list.

        Returns:
            The text, several lines.
        """

    @staticmethod
    def _from_state(state: str) -> Explanation: ...
    def __reduce__(self) -> tuple[Any, tuple[str]]: ...
    def __eq__(self, value: object, /) -> bool: ...

class _ModelLike(Protocol):
    """A model written in Python (see ``modelgap.ModelLike``).

    Optionally it also has ``name``, ``inputs``, ``unit(output)`` and
    ``free_parameters()``: its own unknowns as a sequence of ``EffectParam`` (with an
    optional ``prior``). ``fit`` calibrates them, passing ``predict`` an ``Effect`` of id
    ``calibration`` with their values; ``explain`` fits every candidate jointly with them.
    """

    @property
    def outputs(self) -> Sequence[str]:
        """The names of the measured outputs the model predicts (as in recordings)."""

    def predict(
        self, recording: Recording, effects: Sequence[Effect]
    ) -> Mapping[str, npt.ArrayLike]:
        """Predicts the outputs at the recording's times, driven by its inputs.

        Args:
            recording: The recording: its times (s) and the input signals that drive the model.
            effects: The effects to apply, each at its ``values`` (its ``id`` says which of
                ``candidates()`` it is); effects built in by ``with_effects`` come first.

        Returns:
            A dict of output name to an array of one value per sample.

        Raises:
            ModelError: When the model cannot simulate at these values (a fit steps away).
                Any other exception stops the loop and comes back to the caller as itself.
        """

    def candidates(self) -> Sequence[Candidate]:
        """The ``Candidate`` effects the model could be missing."""

_Model = Union[BondModel, ClothModel, _ModelLike]

@final
class EffectParam:
    """A parameter of a candidate effect: its name, unit, start value, bounds and typical size.

    The typical size is the fit's scale, which also sets its finite-difference steps: give it
    even when the start value is 0.
    """

    def __new__(
        cls,
        name: str,
        *,
        lower: float,
        upper: float,
        initial: Optional[float] = None,
        scale: Optional[float] = None,
        unit: str = "",
        prior: Optional[Tuple[float, float]] = None,
    ) -> EffectParam:
        """Defines a parameter the loop fits.

        Args:
            name: The parameter's name (``R_leak``), the key of ``Effect.values``.
            lower: The lower bound of the fit, in ``unit``; finite.
            upper: The upper bound of the fit, in ``unit``; finite, above ``lower``.
            initial: Where the fit starts, within the bounds; default their midpoint.
            scale: A typical size of the parameter, positive; default a tenth of
                ``upper - lower``.
            unit: The unit (``Ohm``; ``""`` or ``"1"`` for none).
            prior: What is known of the value before the data, a Gaussian ``(mean, std)``
                in ``unit``; ``fit`` weighs it against the recording (for the unknowns a
                model's ``free_parameters()`` lists).

        Raises:
            DataError: For bounds that are not finite or not ordered, an ``initial`` outside
                them, a ``scale`` that is not positive and finite, or a ``prior`` whose
                ``std`` is not positive and finite.
        """

    @property
    def name(self) -> str:
        """The parameter's name."""

    @property
    def unit(self) -> str:
        """The parameter's unit (``""`` or ``"1"`` for none)."""

    @property
    def initial(self) -> float:
        """Where the fit starts, in ``unit``."""

    @property
    def lower(self) -> float:
        """The lower bound, in ``unit``."""

    @property
    def upper(self) -> float:
        """The upper bound, in ``unit``."""

    @property
    def scale(self) -> float:
        """A typical size of the parameter, in ``unit``."""

    @property
    def prior(self) -> Optional[Tuple[float, float]]:
        """A Gaussian prior ``(mean, std)`` in ``unit``, or ``None``."""

@final
class Candidate:
    """An effect a model written in Python may be missing: what its ``candidates()`` lists.

    It has a stable ``id``, a plain ``name``, a ``kind``, where it acts and its parameters.
    """

    def __new__(
        cls,
        id: str,
        name: str,
        params: Sequence[EffectParam],
        *,
        kind: str = "missing-element",
        acts_on: str = "",
    ) -> Candidate:
        """Defines a candidate effect.

        Args:
            id: A stable id (what ``Effect.id`` and ``explain(only=...)`` use).
            name: A plain name for reports.
            params: Its parameters, at least one.
            kind: ``"missing-element"``, ``"parameter-deviation"`` or ``"abrupt-change"``.
            acts_on: Where it acts (for reports).

        Raises:
            DataError: For another ``kind`` or no parameter.
        """

    @property
    def id(self) -> str:
        """The stable id."""

    @property
    def name(self) -> str:
        """The plain name."""

    @property
    def params(self) -> list[str]:
        """The parameters' names, in order."""

    def effect(self, values: dict[str, float]) -> Effect:
        """The effect at ``values``, as the loop passes it to ``predict``.

        To try a model's effect by hand, or make a recording with it.

        Args:
            values: Parameter name to value (in the parameter's unit), every parameter given.

        Returns:
            The effect.

        Raises:
            DataError: When a parameter has no value or a name is not a parameter.
        """

def load_model(
    model: str,
    *,
    set: Optional[dict[str, float]] = None,
    steady_start: bool = False,
    hold: str = "auto",
) -> Union[BondModel, ClothModel]:
    """Loads a model by file or built-in name, as the command line does.

    A bond-graph model file or ``dc-motor``/``buck-motor`` gives a ``BondModel``; a scene
    file (a ``[cloth]`` table) or ``corner``/``two-corners``/``drape`` a ``ClothModel``. The
    GIL is released while loading.

    Args:
        model: A file path, or the name of a built-in model or reference scene.
        set: Bond-graph parameters or input defaults to change first, name to value in the
            parameter's unit (SI).
        steady_start: Bond graphs: start predictions at the steady state under the
            recording's first input values instead of at rest.
        hold: Bond graphs: how recorded inputs are held between samples: ``"auto"`` (each
            input that steps held at its samples' values, any other the way the model
            predicts the recording better; see ``BondModel.hold_notes``), ``"zoh"`` (zero
            order), ``"linear"`` or ``"cubic"`` (a smooth cubic through the samples).

    Returns:
        A ``BondModel`` or a ``ClothModel``.

    Raises:
        DataError: For a file that cannot be read (naming the file, line and element), an
            unknown name, a bad ``hold``, a ``set`` of an unknown or unphysical value, or
            ``set``/``steady_start``/``hold`` given for a cloth scene (which takes none).
    """

def load_recording(path: _Path, model: _Model) -> Recording:
    """Reads a recording the way ``model`` takes it.

    A signals file (``.csv``, ``.mcap``, ``.parquet``) for a bond-graph model or a model
    written in Python; a marker file (``t,id,x,y,z`` CSV or ``/markers`` MCAP, every id
    checked against the grid) for a ``ClothModel``, turned into signals ``m{id}.x|y|z`` (m).
    The GIL is released while reading.

    Args:
        path: The file.
        model: The model the recording is for.

    Returns:
        The recording.

    Raises:
        DataError: For a file that cannot be read or does not fit the model.
        TypeError: When ``model`` is not a model.
    """

def compare(
    model: _Model,
    rec: Recording,
    *,
    noise: Optional[dict[str, float]] = None,
    band_sigmas: float = 4.0,
    band_fraction: Optional[float] = None,
    min_window: Optional[float] = None,
    predictability: bool = True,
) -> Comparison:
    """Simulates the model on the recording's inputs and holds it against its outputs.

    Every output the model predicts and the recording measures is compared: residual
    statistics, the noise floor, and the windows where the residual leaves its band. The GIL
    is released while the model runs (a Python model takes it for each ``predict``).

    Args:
        model: A ``BondModel``, a ``ClothModel`` or a model written in Python
            (``modelgap.ModelLike``).
        rec: The recording: the model's inputs and measured outputs.
        noise: Known noise floors, output name to σ in the output's unit (positive,
            finite). Outputs not named get a floor estimated from the measurement's
            high-frequency part; names that are not compared outputs are ignored.
        band_sigmas: The half-width of the failure band in noise floors (positive).
        band_fraction: Instead of ``band_sigmas``: the paper's band, this fraction of the
            magnitude of the prediction's steady state (the mean of its last 10 % of
            samples).
        min_window: The shortest failure window (s): excursions separated by less are
            merged, shorter ones dropped. Default five mean sample periods.
        predictability: Widen the band by the model's own predictability band where it has
            one (a cloth model near a snap), so only failures beyond it count; bond-graph and
            Python models have none.

    Returns:
        The ``Comparison``.

    Raises:
        DataError: For a noise floor that is not positive and finite, a ``band_sigmas`` that
            is not positive, a recording that measures none of the model's outputs, or fewer
            than 8 samples when a floor must be estimated.
        ModelError: When the model cannot be simulated on the recording.
        ConvergenceError: When a bond-graph simulation fails or has no steady state to
            start from.
        TypeError: When ``model`` is not a model. An exception other than ``ModelError``
            raised by a Python model's ``predict`` comes back as itself.
    """

def explain(
    model: _Model,
    rec: Recording,
    *,
    noise: Optional[dict[str, float]] = None,
    significance: float = 10.0,
    max_effects: int = 2,
    only: Optional[list[str]] = None,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> Explanation:
    """Fits every candidate effect the model offers to the recording and says which is missing.

    Each candidate (``model.candidates()``) is fitted in parallel by bounded least squares on
    the residual weighted by the noise floors, and scored by the error it removes penalised
    by its number of parameters (a BIC difference). The best candidate is chosen when its
    score beats ``significance``; when it leaves the residual above the noise floor, a second
    effect is fitted jointly on top of it. An output is at its floor when its RMS is within
    1.3 × its noise floor (a fixed factor; with more than three outputs, their quadratic mean
    within 1.3 and each within 2.6) and its residual looks like noise: no failure window, no
    correlation with the inputs, no bias. The GIL is released during the fits, so
    ``explain`` runs in parallel on threads.

    Args:
        model: A ``BondModel``, a ``ClothModel`` or a model written in Python
            (``modelgap.ModelLike``).
        rec: The recording: the model's inputs and measured outputs (at least one output
            in common).
        noise: Known noise floors, output name to σ in the output's unit (positive, finite).
            They weight the fits and are the floor the verdict judges against. Outputs not
            named get a floor estimated from the measurement's high-frequency part; names
            that are not outputs of the model are ignored.
        significance: The score (a BIC difference, dimensionless) the best candidate must
            exceed to be chosen; also the gain a second effect must add to be chosen with
            it, and the margin by which a candidate with more parameters must beat a simpler
            one to rank above it. Default 10 ("very strong evidence"); not checked.
        max_effects: 2 (the default) lets a second effect be fitted on top of the first
            when the first leaves the residual above the floor; with 1 at most one effect is
            chosen. Other values raise ``DataError`` (a negative one ``OverflowError``).
        only: The candidate ids to fit (``"coulomb@1m"``, ``"deviation:R"``); the others
            are skipped, for the second effect too. ``None`` or an empty list fits every
            candidate. An id that is not on the model's menu raises ``DataError`` naming it
            and listing the menu.
        progress: Called as ``progress(done, total)`` with the candidate fits finished and
            the number to fit, on the calling thread, polled every 50 ms and only when the
            counts changed (so some counts are skipped; the last call is ``(total, total)``,
            and no call is made when nothing is fitted). The fits of a second effect are not
            counted. Its return value is ignored; an exception it raises stops the fits and
            is raised again once they have stopped. Works with ``tqdm``.

    Returns:
        The ``Explanation``: verdict, ranked candidates, chosen effects. A candidate whose
        fit fails is ranked last with its ``error``, not raised.

    Raises:
        DataError: For a noise floor that is not positive and finite, or a recording that
            measures none of the model's outputs.
        ModelError: When the model as given cannot be simulated on the recording.
        ConvergenceError: When a bond-graph simulation of the model as given fails or has no
            steady state to start from.
        KeyboardInterrupt: On Ctrl-C: the fits stop, and it is raised once they have
            stopped (no explanation is returned).
        TypeError: When ``model`` is not a model. An exception raised by ``progress``, or one
            other than ``ModelError`` raised by a Python model's ``predict``, stops the run
            and comes back as itself.
    """

def write_report(
    dir: _Path,
    before: Comparison,
    explanation: Optional[Explanation] = None,
    after: Optional[Comparison] = None,
) -> Path:
    """Writes the HTML report of a loop and the comparison as MCAP.

    ``report.html`` tells what failed, what is missing and what fixing it gives;
    ``comparison.mcap`` holds the measured and predicted signals (and those after the fix)
    for Foxglove, with time shifted to start at 0. The GIL is released while writing.

    Args:
        dir: The directory to write into; created when missing.
        before: The comparison of the model as given.
        explanation: The explanation of the same recording, if any.
        after: The comparison of the fixed model, if any.

    Returns:
        The path of ``report.html``.

    Raises:
        DataError: When the directory or a file cannot be written.
    """

_Drive = Union[float, tuple[npt.ArrayLike, npt.ArrayLike], tuple[Any, ...]]

@final
class BondModel:
    """A bond-graph model: what ``compare`` and ``explain`` hold against a recording.

    Make one with ``BondModel.load(path)`` (a model file), ``BondModel.from_toml(text)``,
    ``BondModel.dc_motor()``, ``BondModel.buck_motor()`` or ``BondModel.builtin(name)``.
    Effects found by ``explain`` are added with ``with_effects``, which returns a new model.
    Models pickle (file text, start, hold and effects).
    """

    @staticmethod
    def load(path: _Path) -> BondModel:
        """Reads a bond-graph model file (TOML). The GIL is released while reading.

        Args:
            path: The model file.

        Returns:
            The model, starting at rest, inputs held ``"zoh"``.

        Raises:
            DataError: For a file that cannot be read, or content that does not make a model
                (naming the line and column).
        """

    @staticmethod
    def from_toml(text: str) -> BondModel:
        """A model from the text of a model file.

        Args:
            text: The TOML text of a model file.

        Returns:
            The model, starting at rest, inputs held ``"zoh"``.

        Raises:
            DataError: For text that does not make a model (naming the line and column).
        """

    @staticmethod
    def dc_motor() -> BondModel:
        """The DC motor of the diagnosis paper (12 V, permanent magnet).

        R = 1 Ohm, L = 5 mH, k = 0.05 N m/A, J = 1e-4 kg m², beta = 1e-5 N m s/rad.

        Returns:
            The model: inputs ``V`` (V, default 12) and load torque ``tau_L`` (N m, default
            0), outputs ``i`` (A) and ``omega`` (rad/s).
        """

    @staticmethod
    def buck_motor() -> BondModel:
        """The buck converter feeding the DC motor (section 5 of the paper).

        Returns:
            The model: inputs ``Vs`` (V, default 24), the switch modulus ``m`` (default 0.5:
            an averaged duty cycle, or a PWM signal in {0, 1}) and ``tau_L`` (N m), outputs
            ``i`` (A), ``omega`` (rad/s) and ``v_c`` (V).
        """

    @staticmethod
    def builtin(name: str) -> BondModel:
        """A built-in model by name.

        Args:
            name: ``"dc-motor"`` or ``"buck-motor"`` (see ``builtins()``; ``_`` may stand
                for ``-``).

        Returns:
            The model.

        Raises:
            DataError: For an unknown name (naming the built-ins).
        """

    @staticmethod
    def builtins() -> list[str]:
        """The names of the built-in models.

        Returns:
            The names, for ``builtin``.
        """

    def with_start(self, start: str) -> BondModel:
        """The same model with predictions starting elsewhere.

        Args:
            start: ``"rest"``, or ``"steady"`` (also ``"steady-state"``, ``"steady_state"``):
                the steady state under the recording's first input values.

        Returns:
            A new model.

        Raises:
            DataError: For another ``start``.
        """

    def with_hold(self, hold: str) -> BondModel:
        """The same model with recorded inputs held another way between samples.

        Args:
            hold: ``"auto"`` (each input that steps held at its samples' values, any other
                the way the model predicts each recording better), ``"zoh"`` (also
                ``"zero"``; zero-order hold, for commanded inputs), ``"linear"`` (straight
                lines between samples) or ``"cubic"`` (a smooth cubic through them, for
                sampled analog inputs).

        Returns:
            A new model.

        Raises:
            DataError: For another ``hold``.
        """

    def hold_notes(self, rec: Recording) -> list[str]:
        """How the hold ``"auto"`` holds each input ``rec`` records, and why.

        Args:
            rec: A recording of the model's inputs and outputs.

        Returns:
            One sentence per recorded input that is not constant (the notes ``modelgap
            explain`` prints); empty when the model's hold is given.

        Raises:
            ModelError: When the model cannot be built.
        """

    def with_effects(self, effects: list[Effect]) -> BondModel:
        """A new model with the effects (from ``Explanation.effects``) built in, after any
        built in before.

        Args:
            effects: The effects, each with its fitted values.

        Returns:
            A new model; this one is unchanged.

        Raises:
            ModelError: For an effect this model does not offer or values it cannot take
                (out of the candidate's bounds).
        """

    def set(self, name: str, value: float) -> None:
        """Sets a parameter (or an input's default) of the model as loaded, in place.

        Args:
            name: The parameter or input name.
            value: The new value, in its unit (``units``).

        Raises:
            DataError: For an unknown name or an unphysical value.
        """

    def free(self, name: str, bounds: Optional[Tuple[float, float]] = None) -> None:
        """Marks a parameter unknown, for ``modelgap.fit`` to calibrate, in place.

        Args:
            name: The parameter name.
            bounds: ``(lower, upper)`` in the parameter's unit; ``None`` gives from 0 to
                1000 times its value, its sign kept.

        Raises:
            DataError: For an unknown parameter, bounds that are not finite and ordered or
                leave out its value, or no bounds for a value of 0.
        """

    @property
    def name(self) -> str:
        """The model's name."""

    @property
    def start(self) -> str:
        """Where predictions start: ``"rest"`` or ``"steady"``."""

    @property
    def hold(self) -> str:
        """How recorded inputs are held: ``"auto"``, ``"zoh"``, ``"linear"`` or ``"cubic"``."""

    @property
    def params(self) -> dict[str, float]:
        """Parameter values by name (SI units, see ``units``), effects included; a fresh
        dict."""

    @property
    def units(self) -> dict[str, str]:
        """Parameter units by name (``"Ohm"``, ``"H"``, ``"kg m^2"``)."""

    @property
    def inputs(self) -> dict[str, float]:
        """Input defaults by name, each in the input's unit."""

    @property
    def outputs(self) -> list[str]:
        """The measured outputs, in order."""

    @property
    def effects(self) -> list[Effect]:
        """The effects built in so far, in order."""

    def candidates(self) -> list[dict[str, Any]]:
        """The candidate effects ``explain`` fits.

        Returns:
            Dicts with ``id``, ``name``, ``kind``, ``acts_on`` and ``params`` (the parameter
            names).
        """

    def equations(self, latex: bool = False) -> str:
        """The causal equations (and the state equations) in the paper's notation.

        Args:
            latex: Give LaTeX (an ``align*`` environment) instead of plain text.

        Returns:
            The equations.

        Raises:
            ModelError: When causality cannot be assigned or the equations derived.
        """

    def _repr_latex_(self) -> str: ...
    def state_space(self) -> dict[str, Any]:
        """The linear state space at the default inputs (linearised at the steady state for a
        model that is not LTI, at zero when there is none).

        Returns:
            A dict of ``A``, ``B``, ``C``, ``D`` (fresh float64 arrays, SI units) and the
            ``states``, ``inputs`` and ``outputs`` names.

        Raises:
            ModelError: When the model cannot be compiled.
        """

    def eigenvalues(self) -> npt.NDArray[np.complex128]:
        """The eigenvalues of ``A`` of ``state_space()``.

        Returns:
            A complex array (1/s).

        Raises:
            ModelError: When the model cannot be compiled.
        """

    def steady_state(self, inputs: Optional[dict[str, float]] = None) -> dict[str, float]:
        """The steady state under the given input values (defaults for the others).

        Args:
            inputs: Input name to value, in the input's unit.

        Returns:
            A dict of the states and outputs by name (SI units).

        Raises:
            DataError: For an unknown input.
            ConvergenceError: When there is no steady state.
            ModelError: When the model cannot be compiled.
        """

    def simulate(
        self,
        t: npt.ArrayLike,
        inputs: Optional[dict[str, _Drive]] = None,
        *,
        solver: str = "auto",
        faults: Optional[list[tuple[str, float, float]]] = None,
        steady_start: bool = False,
        hold: str = "linear",
        states: bool = False,
    ) -> Recording:
        """Simulates the model (effects included) and records its inputs and outputs.

        The GIL is released while it runs.

        Args:
            t: The sample times (s), 1-D.
            inputs: Input name to drive; the others keep their defaults. A drive is a number
                (constant, in the input's unit), ``(t, values)`` arrays (held by ``hold``
                between samples) or ``("pwm", duty, frequency_hz[, high, low])`` (``high``
                defaults to 1, ``low`` to 0, not to the input's default).
            solver: ``"auto"``, ``"exact"``, ``"dopri5"`` or ``"rosenbrock"``.
            faults: Abrupt changes ``(parameter, new_value, at_s)``: the parameter (or input)
                takes ``new_value`` (its unit) from ``at_s`` (s) on.
            steady_start: Start at the steady state under the inputs' starting values instead
                of at rest.
            hold: How ``(t, values)`` drives are held between samples: ``"linear"``,
                ``"zoh"`` (also ``"zero"``) or ``"cubic"``. The model's own ``hold`` is not
                used here.
            states: Record the state variables too.

        Returns:
            A ``Recording`` of the inputs, then the outputs (and the states with
            ``states=True``).

        Raises:
            DataError: For an unknown input or fault parameter, a bad drive, ``solver`` or
                ``hold``, or bad times.
            ModelError: When the model cannot be compiled or a law or state is not finite.
            ConvergenceError: When the ODE solver fails or there is no steady state to start
                from.
        """

    def causal_graph_dot(self) -> str:
        """The causal graph as Graphviz DOT.

        Returns:
            The DOT text.

        Raises:
            ModelError: When causality cannot be assigned or the equations derived.
        """

    def causal_table(self) -> str:
        """The causal graph's antecedents/consequents table.

        Returns:
            The table as text.

        Raises:
            ModelError: When causality cannot be assigned or the equations derived.
        """

    def fault_tree(self, output: str, qual: str) -> str:
        """The fault tree of a measured output deviating in one direction.

        Args:
            output: A measured output's name.
            qual: The deviation: ``"+"``, ``"-"`` or ``"0"``.

        Returns:
            The tree as text.

        Raises:
            DataError: For another ``qual``.
            ModelError: For an output that is not measured, or a graph whose causality cannot
                be assigned.
        """

    def diagnose(
        self,
        rec: Recording,
        *,
        threshold: float = 0.02,
        noise_sigmas: Optional[float] = None,
        persistence: int = 3,
        steady_start: bool = False,
    ) -> Diagnosis:
        """The paper's qualitative diagnosis of a recording.

        Residuals from a parallel simulation of the model, detection against a band, fault
        trees and temporal signatures. The GIL is released while it runs.

        Args:
            rec: The recording: the model's inputs and measured outputs.
            threshold: The band as a fraction (dimensionless) of the magnitude of each
                nominal output's steady state (the mean of its last 10 %); the paper's 2 %.
            noise_sigmas: Instead of ``threshold``: the band as this many noise σ of each
                measurement (estimated from it).
            persistence: Consecutive samples out of the band that make a detection.
            steady_start: Start the parallel model at its steady state under the recording's
                first input values instead of at rest.

        Returns:
            The ``Diagnosis``.

        Raises:
            DataError: For a recording that does not fit the model.
            ModelError: When the model cannot be simulated.
            ConvergenceError: When the simulation fails or there is no steady state to start
                from.
        """

    def arrs(self) -> str:
        """Analytical redundancy relations, the fault signature matrix, detectability and
        isolability.

        Returns:
            The text.

        Raises:
            ModelError: When the equations cannot be derived.
        """

    def to_toml(self) -> str:
        """The model as a model file (TOML), headed by a comment per effect built in.

        Returns:
            The TOML text (``from_toml`` reads it back).
        """

    def save(self, path: _Path) -> None:
        """Writes ``to_toml()`` to a file (atomically). The GIL is released while writing.

        Args:
            path: The file to write.

        Raises:
            DataError: When the file cannot be written.
        """

    @staticmethod
    def _from_state(text: str, start: str, hold: str, effects: str) -> BondModel: ...
    def __reduce__(self) -> tuple[Any, tuple[str, str, str, str]]: ...

@final
class Diagnosis:
    """The result of ``BondModel.diagnose``: detection, fault trees, signatures and the
    hypothesis sets."""

    @property
    def hypotheses(self) -> list[str]:
        """The final hypothesis set, each as a parameter and its deviation (``R+``)."""

    @property
    def parameters(self) -> list[str]:
        """The parameters of the final hypothesis set, sorted."""

    @property
    def detected_at(self) -> Optional[float]:
        """When the first residual left its band (s), or ``None``."""

    @property
    def behaviour(self) -> str:
        """``"zero"``, ``"transitory"`` or ``"permanent"``."""

    @property
    def residuals(self) -> list[dict[str, Any]]:
        """Per output, a dict of ``output``, ``band`` (output's unit), ``detected_at`` (s or
        ``None``), ``first_deviation``, ``behaviour`` and ``residual`` (a fresh float64
        array)."""

    @property
    def stages(self) -> list[tuple[float, str, str]]:
        """The hypothesis sets as the measurements left their bands: ``(at_s, from_trees,
        after_signatures)`` with the sets as text."""

    @property
    def warnings(self) -> list[str]:
        """Non-fatal findings."""

    def report(self) -> str:
        """The diagnosis as a report.

        Returns:
            The report as text.
        """

def table7() -> list[dict[str, Any]]:
    """Runs the paper's Table 7: each ±20 % fault of the buck converter + motor simulated and
    diagnosed. The GIL is released while it runs.

    Returns:
        One dict per fault, with ``fault``, ``detected_at`` (s), ``deviations``,
        ``hypotheses``, ``parameters``, ``behaviour``, ``paper_parameters``,
        ``paper_behaviour``, ``contains_fault``, ``same_set``, ``same_behaviour`` and
        ``stages``.

    Raises:
        ModelError: When a simulation fails.
        ConvergenceError: When a simulation fails to converge.
    """

def hidden_cases() -> list[str]:
    """The names of the hidden-effect cases (``coulomb``, ``load``, …, ``nothing``).

    Returns:
        The names, for ``hidden_recording``.
    """

def hidden_recording(case: str, seed: int = 1, duration: float = 4.0) -> Recording:
    """A recording of a built-in motor with a hidden effect (or none, for ``nothing``).

    Sampled at 1 kHz under a reversing voltage profile, with a sensor lag and white plus
    coloured noise on every output: what ``explain`` is judged on. The GIL is released while
    it runs.

    Args:
        case: A name of ``hidden_cases()``.
        seed: The noise seed (non-negative).
        duration: The length (s), positive.

    Returns:
        The recording: the inputs and measured outputs.

    Raises:
        DataError: For an unknown case or a duration that is not positive.
    """

# Cloth (re-exported by modelgap.cloth).

_I64 = npt.NDArray[np.int64]
_Indices = Union[npt.ArrayLike, list[int]]
_Vec3 = Union[npt.ArrayLike, tuple[float, float, float]]
_Progress = Optional[Callable[[int, int], Any]]

@final
class ClothMesh:
    """A cloth mesh before it enters a world: a particle per vertex, a distance constraint per
    edge, the triangles, the pinned (static) vertices.

    Build one with ``ClothMesh(vertices, triangles)``, ``ClothMesh.grid(nx, nz, spacing)``
    or ``ClothMesh.load_obj(path)``. Meshes pickle.
    """

    def __new__(
        cls,
        vertices: npt.ArrayLike,
        triangles: npt.ArrayLike,
        *,
        particle_mass: float = 0.001,
        pins: Optional[_Indices] = None,
    ) -> ClothMesh:
        """A mesh from numpy arrays; each triangle side becomes a constraint.

        Args:
            vertices: Vertex positions (m), shape ``(n, 3)``.
            triangles: Vertex indices, shape ``(m, 3)``, integers.
            particle_mass: The mass of every particle (kg), positive; default 1 g.
            pins: Indices of the vertices to pin (static).

        Raises:
            DataError: For a bad shape, non-integer indices, a vertex index past the mesh, a
                mass that is not positive, or a mesh that cannot work (naming the vertex or
                edge).
        """

    @staticmethod
    def grid(
        nx: int,
        nz: int,
        spacing: float,
        *,
        particle_mass: float = 0.001,
        pins: Optional[_Indices] = None,
        shear: bool = False,
        bend: bool = False,
        origin: Optional[_Vec3] = None,
    ) -> ClothMesh:
        """A flat grid in the x–z plane: vertex ``row * nx + col`` at
        ``origin + (col, 0, row) * spacing``.

        Args:
            nx: Vertices along x.
            nz: Vertices along z.
            spacing: The distance between neighbouring vertices (m).
            particle_mass: The mass of every particle (kg); default 1 g.
            pins: Indices of the vertices to pin (static).
            shear: Add both diagonals of every cell as constraints.
            bend: Add edges that skip a vertex along x and z as constraints.
            origin: Where vertex 0 sits (m); default ``(0, 0, 0)``.

        Returns:
            The mesh (structural edges along x and z, plus those asked for).

        Raises:
            DataError: For sizes, a spacing, a mass or pins that cannot work.
        """

    @staticmethod
    def load_obj(
        path: _Path, *, particle_mass: float = 0.001, pins: Optional[_Indices] = None
    ) -> ClothMesh:
        """Reads an OBJ file: ``v`` lines become particles, the faces' sides constraints.

        The GIL is released while reading.

        Args:
            path: The OBJ file (positions in m).
            particle_mass: The mass of every particle (kg); default 1 g.
            pins: Indices of the vertices to pin (static).

        Returns:
            The mesh.

        Raises:
            DataError: For a file that cannot be read, a malformed line (naming it), or a
                mesh that cannot work.
        """

    @staticmethod
    def from_obj(
        text: str, *, particle_mass: float = 0.001, pins: Optional[_Indices] = None
    ) -> ClothMesh:
        """Reads OBJ text, as ``load_obj`` reads a file.

        Args:
            text: The OBJ text (positions in m).
            particle_mass: The mass of every particle (kg); default 1 g.
            pins: Indices of the vertices to pin (static).

        Returns:
            The mesh.

        Raises:
            DataError: For a malformed line (naming it) or a mesh that cannot work.
        """

    def pin(self, vertex: int) -> None:
        """Pins a vertex (makes its particle static), in place.

        Args:
            vertex: The vertex index.

        Raises:
            DataError: For a vertex past the mesh. Neighbouring pins are allowed: the edge
                between them is not a constraint.
        """

    @property
    def n_vertices(self) -> int:
        """The number of vertices (particles)."""

    @property
    def n_edges(self) -> int:
        """The number of edges (distance constraints)."""

    @property
    def vertices(self) -> _F64:
        """Vertex positions (m), a fresh ``(n, 3)`` float64 array."""

    @property
    def masses(self) -> _F64:
        """Particle masses (kg), a fresh ``(n,)`` float64 array."""

    @property
    def edges(self) -> _I64:
        """Edges as vertex pairs, a fresh ``(k, 2)`` int64 array."""

    @property
    def triangles(self) -> _I64:
        """Triangles as vertex indices, a fresh ``(m, 3)`` int64 array."""

    @property
    def pinned(self) -> list[int]:
        """The pinned vertices, sorted."""

    @staticmethod
    def _from_parts(
        vertices: npt.ArrayLike,
        masses: npt.ArrayLike,
        edges: npt.ArrayLike,
        triangles: npt.ArrayLike,
        pinned: _Indices,
    ) -> ClothMesh: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...

@final
class Collider:
    """A static collider: a shape and a Coulomb friction coefficient.

    Made by ``Collider.plane``, ``ball``, ``cuboid``, ``capsule`` or ``trimesh``; colliders
    compare equal by value.
    """

    @staticmethod
    def plane(point: _Vec3, normal: _Vec3, *, friction: float = 0.0) -> Collider:
        """The solid half-space behind a plane.

        Args:
            point: A point of the plane (m).
            normal: The outward normal (normalised here; not zero).
            friction: The Coulomb friction coefficient (dimensionless).

        Returns:
            The collider.

        Raises:
            DataError: For a zero normal, non-finite numbers or a bad friction.
        """

    @staticmethod
    def ball(center: _Vec3, radius: float, *, friction: float = 0.0) -> Collider:
        """A solid ball.

        Args:
            center: Its centre (m).
            radius: Its radius (m).
            friction: The Coulomb friction coefficient (dimensionless).

        Returns:
            The collider.

        Raises:
            DataError: For a radius or friction that cannot work.
        """

    @staticmethod
    def cuboid(
        half_extents: _Vec3,
        *,
        center: Optional[_Vec3] = None,
        rotation: Optional[_Vec3] = None,
        friction: float = 0.0,
    ) -> Collider:
        """A solid box.

        Args:
            half_extents: Half its size along its local axes (m).
            center: Its centre (m); default the origin.
            rotation: Its rotation as an axis × angle vector (rad); default none.
            friction: The Coulomb friction coefficient (dimensionless).

        Returns:
            The collider.

        Raises:
            DataError: For sizes or a friction that cannot work.
        """

    @staticmethod
    def capsule(a: _Vec3, b: _Vec3, radius: float, *, friction: float = 0.0) -> Collider:
        """A solid capsule: the points within ``radius`` of the segment ``a``–``b``.

        Args:
            a: One end of the segment (m).
            b: The other end (m).
            radius: The radius (m).
            friction: The Coulomb friction coefficient (dimensionless).

        Returns:
            The collider.

        Raises:
            DataError: For a radius or friction that cannot work.
        """

    @staticmethod
    def trimesh(
        vertices: npt.ArrayLike,
        triangles: npt.ArrayLike,
        *,
        shell_thickness: Optional[float] = None,
        friction: float = 0.0,
    ) -> Collider:
        """A triangle mesh: a solid when closed, a surface with a shell when open.

        Args:
            vertices: Vertex positions (m), shape ``(n, 3)``.
            triangles: Vertex indices, shape ``(m, 3)``, counter-clockwise seen from outside.
            shell_thickness: The thickness of an open surface (m); default 0.01 m.
            friction: The Coulomb friction coefficient (dimensionless).

        Returns:
            The collider.

        Raises:
            DataError: For a bad shape, an index past the vertices, or numbers that cannot
                work.
        """

    @property
    def shape(self) -> str:
        """``"plane"``, ``"ball"``, ``"cuboid"``, ``"capsule"`` or ``"trimesh"``."""

    @property
    def geometry(self) -> dict[str, Any]:
        """The shape's numbers (m).

        ``point`` and ``normal`` of a plane; ``center`` and ``radius`` of a ball;
        ``half_extents``, ``center`` and ``rotation`` (axis × angle, rad) of a cuboid; ``a``,
        ``b`` and ``radius`` of a capsule; ``vertices`` (local), ``triangles``, ``closed``
        and ``shell_thickness`` of a triangle mesh.
        """

    @property
    def friction(self) -> float:
        """The Coulomb friction coefficient (dimensionless)."""

    def with_friction(self, friction: float) -> Collider:
        """The same collider with another friction coefficient.

        Args:
            friction: The Coulomb friction coefficient (dimensionless).

        Returns:
            A new collider.

        Raises:
            DataError: For a friction that cannot work.
        """

    def signed_distance(self, point: _Vec3) -> float:
        """The signed distance of a point to the collider's surface.

        Args:
            point: The point (m).

        Returns:
            The distance (m), negative inside.

        Raises:
            DataError: For a point that is not three finite numbers.
        """

    def __eq__(self, value: object, /) -> bool: ...

@final
class SolverParams:
    """Parameters of the cloth solver: a value (change one with ``replace``).

    Parameters compare equal by value and pickle.
    """

    def __new__(
        cls,
        *,
        method: str = "newton",
        stretch_tolerance: float = 1e-4,
        max_iterations: int = 1000,
        gravity: Optional[_Vec3] = None,
        velocity_iterations: int = 0,
        warm_start: bool = True,
        refactor_ratio: float = 0.3,
        contact_tolerance: float = 1e-4,
        integrator: str = "impulse",
    ) -> SolverParams:
        """Sets the solver's parameters (keywords only).

        Args:
            method: ``"newton"`` (a global solve), ``"gauss-seidel"`` (also
                ``"gauss_seidel"``; the paper's any-time iteration) or ``"strips"`` (the
                paper's acyclic strips).
            stretch_tolerance: The allowed relative stretch of every constraint at the end of
                a converged step (dimensionless; 1e-4 is 0.01 %).
            max_iterations: The iteration limit per step (at least 1); running out is
                reported (``StepReport.converged``), not raised.
            gravity: Gravity (m/s²); default ``(0, -9.81, 0)``. A world refuses to step
                with more than 1000 m/s² in magnitude.
            velocity_iterations: Sweeps of the velocity part of the constraints per step
                (0: off).
            warm_start: Start each step from the last step's impulses.
            refactor_ratio: Newton only: refactor when an iteration shrinks the residual by
                less than this factor, in (0, 1).
            contact_tolerance: The allowed penetration into colliders (m), positive.
            integrator: ``"impulse"`` (the paper's step, first order) or ``"bdf2"`` (second
                order; a step that does not converge as BDF2 is taken again as an impulse
                step, ``StepReport.first_order``).

        Raises:
            DataError: For an unknown method or integrator, or a value out of range.
        """

    def replace(self, **changes: Any) -> SolverParams:
        """The same parameters with some changed.

        Args:
            changes: Keywords of the constructor and their new values.

        Returns:
            New parameters.

        Raises:
            DataError: For a keyword that is not a parameter, or a value out of range.
        """

    def kwargs(self) -> dict[str, Any]:
        """The parameters as a dict of the constructor's keywords.

        Returns:
            A fresh dict; ``SolverParams(**p.kwargs()) == p``.
        """

    @property
    def method(self) -> str:
        """``"newton"``, ``"gauss-seidel"`` or ``"strips"``."""

    @property
    def stretch_tolerance(self) -> float:
        """The allowed relative stretch at the end of a converged step (dimensionless)."""

    @property
    def max_iterations(self) -> int:
        """The iteration limit per step."""

    @property
    def gravity(self) -> tuple[float, float, float]:
        """Gravity (m/s²)."""

    @property
    def velocity_iterations(self) -> int:
        """Sweeps of the velocity part per step."""

    @property
    def warm_start(self) -> bool:
        """Whether a step starts from the last step's impulses."""

    @property
    def refactor_ratio(self) -> float:
        """Newton: refactor when an iteration shrinks the residual by less than this factor."""

    @property
    def contact_tolerance(self) -> float:
        """The allowed penetration into colliders (m)."""

    @property
    def integrator(self) -> str:
        """``"impulse"`` (the paper's step) or ``"bdf2"`` (second order)."""

    @staticmethod
    def _from_state(
        method: str,
        stretch_tolerance: float,
        max_iterations: int,
        gravity: tuple[float, float, float],
        velocity_iterations: int,
        warm_start: bool,
        refactor_ratio: float,
        contact_tolerance: float,
        integrator: str,
    ) -> SolverParams: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...
    def __eq__(self, value: object, /) -> bool: ...

@final
class StepReport:
    """What ``ClothWorld.step`` did over its steps: summed iterations, the worst stretch,
    converged only if every step converged. Reports pickle."""

    @property
    def steps(self) -> int:
        """The steps taken (fewer than asked when stopped)."""

    @property
    def iterations(self) -> int:
        """The iterations used, summed over the steps (Gauss–Seidel or strip sweeps, Newton
        solves)."""

    @property
    def max_stretch(self) -> float:
        """The largest relative stretch of any constraint at the end of any step
        (dimensionless)."""

    @property
    def converged(self) -> bool:
        """Whether every step met its tolerances."""

    @property
    def factorizations(self) -> int:
        """Numeric factorisations (Newton only)."""

    @property
    def fallback_sweeps(self) -> int:
        """Gauss–Seidel sweeps after a failed Newton step (Newton only)."""

    @property
    def n_contacts(self) -> int:
        """The most particles in contact with a collider in one step."""

    @property
    def max_penetration(self) -> float:
        """The deepest penetration into a collider at the end of a step (m)."""

    @property
    def method(self) -> str:
        """The method the last step ran (``"newton"``, ``"gauss-seidel"`` or ``"strips"``):
        not the one asked for when it fell back."""

    @property
    def fallback(self) -> Optional[str]:
        """Why a step ran another method than the one asked for (the first such step), or
        ``None``."""

    @property
    def stagnated(self) -> bool:
        """Whether a step stopped because its error stopped falling: the stretch tolerance
        is below what it can reach (``ClothWorld.stagnation`` says the level)."""

    @property
    def relaxed_tolerance(self) -> Optional[float]:
        """The tolerance held instead of the requested one after a step stagnated (the
        largest over the steps), or ``None``."""

    @property
    def first_order(self) -> bool:
        """Whether a step asked to be BDF2 (``integrator = "bdf2"`` in its scene) did not
        converge as BDF2 and was taken again as the paper's impulse step."""

    @staticmethod
    def _from_state(
        steps: int,
        iterations: int,
        max_stretch: float,
        converged: bool,
        factorizations: int,
        fallback_sweeps: int,
        n_contacts: int,
        max_penetration: float,
        method: str,
        fallback: Optional[str],
        stagnated: bool,
        relaxed_and_first_order: Tuple[Optional[float], bool],
    ) -> StepReport: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...

@final
class ClothWorld:
    """All cloths and colliders of a simulation, stepped together.

    ``world = ClothWorld(SolverParams(...))``; ``cloth = world.add_cloth(mesh)`` returns the
    cloth's id (0, 1, …); ``world.step(100, dt=0.01)`` returns a ``StepReport``;
    ``world.positions(cloth)`` a fresh ``(n, 3)`` float64 array. Stepping releases the GIL,
    stops on Ctrl-C between steps and reports ``progress(done, total)``.
    """

    def __new__(cls, params: Optional[SolverParams] = None) -> ClothWorld:
        """An empty world.

        Args:
            params: The solver parameters; default ``SolverParams()``.
        """

    def add_cloth(self, mesh: ClothMesh) -> int:
        """Adds a cloth: a particle per vertex, a constraint per edge with its current length
        as rest length (an edge between two pinned vertices is not a constraint).

        Args:
            mesh: The mesh (copied).

        Returns:
            The cloth's id (0, 1, …).

        Raises:
            DataError: For a mesh that cannot work (an empty mesh, a zero-length edge, a
                non-finite position).
        """

    def add_collider(self, collider: Collider) -> int:
        """Adds a static collider.

        Args:
            collider: The collider (copied).

        Returns:
            The collider's id (0, 1, …).
        """

    def add_kinematic_pin(
        self, cloth: int, vertex: int, t: npt.ArrayLike, points: npt.ArrayLike
    ) -> None:
        """Makes a pinned vertex follow a path: linear between points, held before the first
        and after the last.

        Args:
            cloth: The cloth's id.
            vertex: The vertex index in that cloth; it must be pinned.
            t: The path's times (s, world time), shape ``(k,)``, strictly increasing.
            points: The path's positions (m), shape ``(k, 3)``.

        Raises:
            DataError: For an unknown cloth, a dynamic vertex, or a bad path.
        """

    def follow_markers(self, cloth: int, markers: MarkerRecording) -> int:
        """Makes every pinned vertex of a cloth whose id is in ``markers`` follow the recorded
        positions (recording time = world time).

        Args:
            cloth: The cloth's id.
            markers: The recording to follow.

        Returns:
            How many pins follow it.

        Raises:
            DataError: For an unknown cloth or markers that cannot be followed.
        """

    def step(
        self, steps: int = 1, *, dt: float = ..., progress: _Progress = None
    ) -> StepReport:
        """Advances the world.

        The GIL is released. Ctrl-C (or an exception from ``progress``) stops it between
        steps, and the steps done stay done. Running out of iterations is reported
        (``converged=False``), not raised.

        Args:
            steps: How many steps to take.
            dt: The step size (s); default 1/60 s.
            progress: Called as ``progress(done, total)`` with the steps done and asked for,
                on the calling thread, polled every 50 ms when the count changed.

        Returns:
            The ``StepReport`` over the steps.

        Raises:
            DataError: For a step size or parameters that cannot work.
            ModelError: When the simulation diverges.
            KeyboardInterrupt: On Ctrl-C. An exception raised by ``progress`` comes back as
                itself.
        """

    def record(
        self,
        steps: int,
        *,
        dt: float = ...,
        cloth: int = 0,
        ids: Optional[_Indices] = None,
        every: int = 1,
        progress: _Progress = None,
    ) -> MarkerRecording:
        """Steps like ``step`` and records the positions of some vertices.

        A frame is recorded at the start, after every ``every`` steps and after the last,
        at the world's time.

        Args:
            steps: How many steps to take.
            dt: The step size (s); default 1/60 s.
            cloth: The cloth's id.
            ids: The vertices to record; default all.
            every: Record a frame every this many steps (at least 1).
            progress: Called as ``progress(done, total)``, as by ``step``.

        Returns:
            The ``MarkerRecording``.

        Raises:
            DataError: For an unknown cloth, a vertex past the cloth, ``every`` of 0, or a
                step that cannot work.
            ModelError: When the simulation diverges.
            KeyboardInterrupt: On Ctrl-C. An exception raised by ``progress`` comes back as
                itself.
        """

    def positions(self, cloth: int = 0) -> _F64:
        """The positions of a cloth's vertices.

        Args:
            cloth: The cloth's id.

        Returns:
            A fresh ``(n, 3)`` float64 array (m).

        Raises:
            DataError: For an unknown cloth.
        """

    def velocities(self, cloth: int = 0) -> _F64:
        """The velocities of a cloth's vertices.

        Args:
            cloth: The cloth's id.

        Returns:
            A fresh ``(n, 3)`` float64 array (m/s).

        Raises:
            DataError: For an unknown cloth.
        """

    def set_positions(self, positions: npt.ArrayLike, cloth: int = 0) -> None:
        """Sets the positions of a cloth's vertices between steps.

        Args:
            positions: The positions (m), shape ``(n, 3)``, one row per vertex.
            cloth: The cloth's id.

        Raises:
            DataError: For an unknown cloth, a bad shape or a non-finite value.
        """

    def set_velocities(self, velocities: npt.ArrayLike, cloth: int = 0) -> None:
        """Sets the velocities of a cloth's vertices between steps.

        Args:
            velocities: The velocities (m/s), shape ``(n, 3)``, one row per vertex.
            cloth: The cloth's id.

        Raises:
            DataError: For an unknown cloth, a bad shape or a non-finite value.
        """

    def triangles(self, cloth: int = 0) -> _I64:
        """A cloth's triangles.

        Args:
            cloth: The cloth's id.

        Returns:
            A fresh ``(m, 3)`` int64 array of vertex indices.

        Raises:
            DataError: For an unknown cloth.
        """

    def inv_masses(self, cloth: int = 0) -> _F64:
        """The inverse masses of a cloth's particles.

        Args:
            cloth: The cloth's id.

        Returns:
            A fresh ``(n,)`` float64 array (1/kg; 0 for pinned vertices).

        Raises:
            DataError: For an unknown cloth.
        """

    def max_stretch(self, cloth: int = 0) -> float:
        """The largest relative stretch of a cloth's constraints now.

        Args:
            cloth: The cloth's id.

        Returns:
            The stretch (dimensionless).

        Raises:
            DataError: For an unknown cloth.
        """

    def momentum(self) -> _F64:
        """The total momentum of all particles.

        Returns:
            A fresh ``(3,)`` float64 array (kg m/s).
        """

    @property
    def time(self) -> float:
        """The simulated time (s)."""

    @property
    def n_cloths(self) -> int:
        """The number of cloths."""

    @property
    def n_particles(self) -> int:
        """The number of particles over all cloths."""

    @property
    def n_constraints(self) -> int:
        """The number of distance constraints over all cloths."""

    @property
    def colliders(self) -> list[Collider]:
        """The colliders, in the order added."""

    @property
    def n_kinematic_pins(self) -> int:
        """The number of kinematic pins."""

    @property
    def stagnation(self) -> Optional[str]:
        """The warning when a step found the stretch tolerance out of reach (the level
        reached and the one held since), or ``None``."""

    @property
    def params(self) -> SolverParams:
        """The solver parameters (assign a new ``SolverParams`` to change them between
        steps)."""

    @params.setter
    def params(self, params: SolverParams) -> None:
        """Replaces the solver parameters.

        Args:
            params: The new parameters, used from the next step on.
        """

@final
class MarkerRecording:
    """The positions of chosen mesh vertices (markers) over time: measured or simulated.

    Arrays read from it are fresh copies; marker recordings compare equal by value and
    pickle.
    """

    def __new__(
        cls, t: npt.ArrayLike, ids: _Indices, positions: npt.ArrayLike
    ) -> MarkerRecording:
        """A marker recording from numpy arrays.

        Args:
            t: Frame times (s), shape ``(n_frames,)``, strictly increasing.
            ids: The markers' vertex indices, shape ``(n_markers,)``.
            positions: Positions (m), shape ``(n_frames, n_markers, 3)``.

        Raises:
            DataError: For a bad shape, non-integer ids, or bad times or positions.
        """

    @staticmethod
    def load(path: _Path) -> MarkerRecording:
        """Reads a ``.csv`` (``t,id,x,y,z``) or ``.mcap`` (topic ``/markers``) marker file.

        The GIL is released while reading.

        Args:
            path: The file; its extension chooses the format.

        Returns:
            The recording.

        Raises:
            DataError: For a file that cannot be read or bad content (naming the line or
                message, the field and the file).
        """

    def save(self, path: _Path) -> None:
        """Writes the recording as ``.csv`` or (zstd) ``.mcap``, chosen by the extension.

        The GIL is released while writing.

        Args:
            path: The file to write.

        Raises:
            DataError: For an unknown extension or a write that fails.
        """

    def to_numpy(self) -> tuple[_F64, _I64, _F64]:
        """The recording as numpy arrays.

        Returns:
            ``(t, ids, positions)``: ``(n_frames,)`` times (s), ``(n_markers,)`` int64 vertex
            ids and ``(n_frames, n_markers, 3)`` positions (m), fresh copies.
        """

    @property
    def t(self) -> _F64:
        """Frame times (s), a fresh array."""

    @property
    def ids(self) -> _I64:
        """Marker ids (vertex indices), a fresh int64 array."""

    @property
    def positions(self) -> _F64:
        """Positions (m), a fresh ``(n_frames, n_markers, 3)`` array."""

    @property
    def n_frames(self) -> int:
        """The number of frames."""

    @property
    def n_markers(self) -> int:
        """The number of markers."""

    def track(self, id: int) -> _F64:
        """The positions of one marker in every frame.

        Args:
            id: The marker's vertex id.

        Returns:
            A fresh ``(n_frames, 3)`` array (m).

        Raises:
            DataError: For an id not recorded.
        """

    def to_recording(self) -> Recording:
        """The markers as a ``Recording`` with signals ``m{id}.x``, ``m{id}.y``, ``m{id}.z``
        (m): what ``compare`` and ``explain`` hold a ``ClothModel`` against.

        Returns:
            The recording.

        Raises:
            DataError: When the markers cannot make a recording.
        """

    @staticmethod
    def from_recording(rec: Recording) -> MarkerRecording:
        """Markers from a ``Recording`` with signals ``m{id}.x|y|z``; other signals are
        ignored.

        Args:
            rec: The recording.

        Returns:
            The marker recording.

        Raises:
            DataError: When the recording holds no complete marker.
        """

    def __len__(self) -> int:
        """The number of frames."""

    def __eq__(self, value: object, /) -> bool: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...

@final
class Scene:
    """A cloth scene: a grid cloth, colliders, solver parameters, a step and a duration.

    ``modelgap.cloth.scene("corner")`` (``corner``, ``two-corners``, ``drape``: the paper's
    30 × 30 mesh), ``Scene.load(path)`` (a TOML scene file) or ``Scene.from_toml(text)``;
    ``resized(nx, nz)`` for a smaller grid, ``world()`` to step it yourself, ``run()`` to run
    it and record its frames. Scenes pickle.
    """

    @staticmethod
    def load(path: _Path) -> Scene:
        """Reads a scene file (TOML). The GIL is released while reading.

        Args:
            path: The scene file.

        Returns:
            The scene.

        Raises:
            DataError: For a file that cannot be read or a bad field (naming the file and the
                field).
        """

    @staticmethod
    def from_toml(text: str, label: str = "scene") -> Scene:
        """A scene from the text of a scene file.

        Args:
            text: The TOML text.
            label: What to call the text in errors.

        Returns:
            The scene.

        Raises:
            DataError: For a bad field (naming it).
        """

    @property
    def name(self) -> str:
        """The scene's short name."""

    @property
    def description(self) -> str:
        """What the scene shows."""

    @property
    def duration(self) -> float:
        """The simulated time (s)."""

    @property
    def dt(self) -> float:
        """The step size (s)."""

    @property
    def n_steps(self) -> int:
        """The steps of ``dt`` that cover ``duration``."""

    @property
    def grid(self) -> tuple[int, int]:
        """The grid's vertices along x and z: ``(nx, nz)``."""

    @property
    def spacing(self) -> float:
        """The distance between neighbouring grid vertices (m)."""

    @property
    def pins(self) -> list[int]:
        """The pinned vertices."""

    @property
    def colliders(self) -> list[Collider]:
        """The colliders."""

    @property
    def params(self) -> SolverParams:
        """The solver parameters."""

    def with_params(self, params: SolverParams) -> Scene:
        """The same scene with other solver parameters.

        Args:
            params: The new parameters.

        Returns:
            A new scene.
        """

    def with_duration(self, duration: float) -> Scene:
        """The same scene with another duration.

        Args:
            duration: The simulated time (s), positive.

        Returns:
            A new scene.

        Raises:
            DataError: For a duration that is not positive and finite.
        """

    def resized(self, nx: int, nz: int) -> Scene:
        """The same scene on another grid over the same width; pins move to the nearest vertex
        at the same relative place.

        Args:
            nx: Vertices along x.
            nz: Vertices along z.

        Returns:
            A new scene.

        Raises:
            DataError: For a grid that cannot work.
        """

    def mesh(self) -> ClothMesh:
        """The scene's mesh, as the world gets it.

        Returns:
            The mesh.

        Raises:
            DataError: For a grid that cannot be built.
        """

    def world(self, markers: Optional[MarkerRecording] = None) -> ClothWorld:
        """A world holding the scene (cloth id 0), to step yourself.

        The scene's effects (drag, damping, point masses, ...) are not in it: ``run()`` and
        ``ClothModel`` step with them.

        Args:
            markers: A recording whose ids the pinned vertices follow, if any.

        Returns:
            The world.

        Raises:
            DataError: For a scene or markers that cannot be built.
        """

    def run(
        self,
        *,
        duration: Optional[float] = None,
        rate: Optional[float] = None,
        markers: Union[str, _Indices, None] = None,
    ) -> ClothRun:
        """Runs the scene from its start and records its frames.

        The GIL is released; Ctrl-C is raised when the run ends (step a ``world()`` to stop
        between steps).

        Args:
            duration: The simulated time (s); default the scene's.
            rate: Frames recorded per second (1/s); default every step.
            markers: The vertices recorded as markers: ``"all"`` (the default), ``"none"``
                (statistics only) or a list of vertex ids.

        Returns:
            The ``ClothRun``.

        Raises:
            DataError: For another ``markers`` string, bad ids or options.
            ModelError: When the simulation diverges.
        """

    def to_toml(self) -> str:
        """The scene as the text of a scene file (``Scene.from_toml`` reads it back).

        The solver's method and limits are not part of a scene file.

        Returns:
            The TOML text.

        Raises:
            DataError: When the scene cannot be written.
        """

    @staticmethod
    def _from_state(text: str, label: str, params: SolverParams) -> Scene: ...
    def __reduce__(self) -> tuple[Any, tuple[str, str, SolverParams]]: ...

@final
class ClothRun:
    """A scene's run (``Scene.run``): the recorded frames, the mesh and what the solver did."""

    @property
    def scene(self) -> str:
        """The scene's name."""

    @property
    def markers(self) -> Optional[MarkerRecording]:
        """The recorded markers (``None`` when none were recorded)."""

    @property
    def frames(self) -> _F64:
        """Every vertex's position in each recorded frame (m), a fresh
        ``(n_frames, n_vertices, 3)`` array."""

    @property
    def triangles(self) -> _I64:
        """The mesh's triangles, a fresh ``(m, 3)`` int64 array."""

    @property
    def edges(self) -> _I64:
        """The mesh's edges, a fresh ``(k, 2)`` int64 array."""

    @property
    def stats(self) -> dict[str, Any]:
        """What the solver did: ``steps``, ``dt`` (s), ``max_stretch``, ``total_iterations``,
        ``max_iterations``, ``mean_iterations``, ``unconverged_steps``, ``n_particles``,
        ``n_constraints``."""

    def save(self, path: _Path) -> None:
        """Writes the run: marker CSV (``.csv``) or MCAP with the mesh for Foxglove (``.mcap``).

        The GIL is released while writing.

        Args:
            path: The file; its extension chooses the format.

        Raises:
            DataError: For an unknown extension or a write that fails.
        """

@final
class ClothModel:
    """A cloth scene as a model of marker recordings.

    What ``modelgap.compare``, ``modelgap.explain`` and ``modelgap.fix`` hold against a
    ``Recording`` of marker signals ``m{id}.x|y|z`` (``MarkerRecording.to_recording()``). It
    predicts by running the scene from its start (simulated time 0 is recording time 0). Its
    candidate effects: air drag, skin friction, wind, damping, bending (the quadratic bending
    rigidity, N m), stretch compliance (warp and weft apart when the scene sets them apart),
    the cloth's mass, a point mass, collider friction, and per ``[[materials]]`` region ``R``
    of the scene its compliance, bending and damping (``compliance@R``, ``bending@R``,
    ``damping@R``). ``with_effects`` returns a new model. Models pickle.
    """

    def __new__(
        cls,
        scene: Scene,
        *,
        method: str = "newton",
        stretch_tolerance: Optional[float] = None,
        max_iterations: int = 200,
        step_divisor: int = 1,
    ) -> ClothModel:
        """A model of a scene.

        Args:
            scene: The scene.
            method: ``"newton"``, ``"gauss-seidel"`` or ``"strips"``.
            stretch_tolerance: The allowed relative stretch (dimensionless, positive);
                ``None``: the scene's.
            max_iterations: The iteration limit per step (at least 1).
            step_divisor: Steps per scene step: the step is the scene's ``dt`` divided by it
                (at least 1).

        Raises:
            DataError: For an unknown method or a value out of range.
        """

    @staticmethod
    def load(path: _Path) -> ClothModel:
        """A model of a scene file, simulated with the default settings.

        The GIL is released while reading.

        Args:
            path: The scene file (TOML).

        Returns:
            The model.

        Raises:
            DataError: For a file that cannot be read or a bad field.
        """

    @staticmethod
    def from_scene(name: str, nx: Optional[int] = None, nz: Optional[int] = None) -> ClothModel:
        """A model of a reference scene, optionally on a smaller grid.

        Args:
            name: ``"corner"``, ``"two-corners"`` or ``"drape"``.
            nx: Vertices along x; default the scene's.
            nz: Vertices along z; default the scene's.

        Returns:
            The model, simulated with the default settings.

        Raises:
            DataError: For an unknown scene or a grid that cannot work.
        """

    def with_effects(self, effects: list[Effect]) -> ClothModel:
        """A new model with the effects (from ``Explanation.effects``) built in, after any
        built in before.

        Args:
            effects: The effects, each with its fitted values.

        Returns:
            A new model; this one is unchanged.

        Raises:
            DataError: For an effect the scene does not offer, or values of the wrong count,
                not finite or outside the effect's bounds.
        """

    @property
    def name(self) -> str:
        """The model's name (the scene's)."""

    @property
    def scene(self) -> Scene:
        """The scene with the effects built in."""

    @property
    def effects(self) -> list[Effect]:
        """The effects built in so far, in order."""

    @property
    def settings(self) -> dict[str, Any]:
        """How it simulates: ``method``, ``stretch_tolerance``, ``max_iterations``,
        ``step_divisor``."""

    @property
    def outputs(self) -> list[str]:
        """The outputs it predicts: ``m{id}.x``, ``m{id}.y``, ``m{id}.z`` (m) for every
        vertex."""

    def candidates(self) -> list[dict[str, Any]]:
        """The candidate effects ``explain`` fits.

        Returns:
            Dicts with ``id``, ``name``, ``kind``, ``acts_on`` and ``params`` (the parameter
            names).
        """

    def simulate(self, t: npt.ArrayLike, ids: Optional[_Indices] = None) -> MarkerRecording:
        """Runs the model's scene (effects included) from its start and records vertices.

        The GIL is released while it runs.

        Args:
            t: The frame times (s), 1-D.
            ids: The vertices to record; default all.

        Returns:
            The ``MarkerRecording``.

        Raises:
            DataError: For bad times or ids.
            ModelError: When the simulation diverges.
        """

    def to_toml(self) -> str:
        """The model as a scene file (TOML), headed by a comment per effect built in.

        Returns:
            The TOML text.

        Raises:
            DataError: When the scene cannot be written.
        """

    @staticmethod
    def _from_state(
        text: str,
        label: str,
        params: SolverParams,
        settings: tuple[str, Optional[float], int, int],
        effects: str,
    ) -> ClothModel: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...

def scene(name: str) -> Scene:
    """A reference scene by name.

    Args:
        name: ``"corner"``, ``"two-corners"`` or ``"drape"`` (see ``scenes()``).

    Returns:
        The scene (the paper's 30 × 30 mesh).

    Raises:
        DataError: For an unknown name.
    """

def scenes() -> list[str]:
    """The names of the reference scenes.

    Returns:
        The names, for ``scene``.
    """


@final
class Calibration:
    """What ``fit`` found: each unknown fitted, the error before and after, and the
    effect that builds the fitted values into the model."""

    @property
    def values(self) -> List[Dict[str, Any]]:
        """One dict per unknown, in fit order: ``name``, ``unit``, ``start``, ``value``,
        ``std_error`` (``None`` when the data do not determine it), ``at_bound``
        (``"lower"``, ``"upper"`` or ``None``), ``bounds`` (``(lower, upper)``) and ``prior``
        (``(mean, std)`` or ``None``)."""

    @property
    def correlation(self) -> List[List[float]]:
        """Correlation matrix of the unknowns, in the order of ``values``."""

    @property
    def rms_before(self) -> Dict[str, float]:
        """RMS of measured − predicted per output with the model's own values."""

    @property
    def rms_after(self) -> Dict[str, float]:
        """RMS of measured − predicted per output with the fitted values."""

    @property
    def termination(self) -> str:
        """Why the fit stopped: ``"converged"``, ``"max-iterations"``, ``"stalled"`` or
        ``"cancelled"``."""

    @property
    def effect(self) -> Effect:
        """The fitted values as an ``Effect`` (kind ``calibration``), for
        ``model.with_effects([cal.effect])``."""

    def to_file_text(self) -> Optional[str]:
        """The calibrated model as a model file's text; ``None`` for a model that is not
        file-based."""


def fit(model: _Model, rec: Recording) -> Calibration:
    """Calibrates the model's unknowns jointly, by simulation error on ``rec``.

    The unknowns are the parameters marked ``free`` (in the model file, or with
    ``BondModel.free``) and the free initial states (``[initial]`` in the file), or what a
    Python model's ``free_parameters()`` lists; a value with a prior is weighed against
    the data (a fit on the data alone first, then with the prior). Each
    output's residual is divided by the standard deviation of its measurement; standard
    errors are widened for the residual's correlation in time; a value that ends on a
    bound is marked and has no standard error. The GIL is released during the fit.

    Args:
        model: The model (a ``BondModel``, or a Python model with ``free_parameters()``).
        rec: A ``Recording`` of the model's inputs and some of its outputs.

    Returns:
        A ``Calibration``.

    Raises:
        ModelError: The model has nothing free, the recording holds none of its outputs
            or an output is constant, or the model cannot be simulated.
        ConvergenceError: The model's start cannot be found (a steady start).
        KeyboardInterrupt: On Ctrl-C.
    """
