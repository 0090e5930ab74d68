"""Plots of the measurement loop with matplotlib (``pip install modelgap[plot]``).

Each function draws on ``ax`` (a new figure's axes when None) and returns the Axes; none
calls ``show()``. matplotlib is imported when a function is first called.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Optional

import numpy as np
import numpy.typing as npt

from ._modelgap import Comparison, Explanation

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

__all__ = ["cloth_error", "measured_vs_model", "ranking", "residual"]


def _axes(ax: Optional[Axes]) -> Axes:
    if ax is not None:
        return ax
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("modelgap.plot needs matplotlib: pip install 'modelgap[plot]'") from e
    _, new = plt.subplots()
    return new


def _label(name: str, unit: str) -> str:
    return f"{name} ({unit})" if unit else name


def measured_vs_model(
    comparison: Comparison,
    output: str,
    ax: Optional[Axes] = None,
    after: Optional[Comparison] = None,
) -> Axes:
    """The measured output with the model's prediction (and the prediction after the
    effects were added, when ``after`` is given)."""
    ax = _axes(ax)
    o = comparison.output(output)
    t = comparison.t
    ax.plot(t, o.measured, color="0.6", lw=0.8, label="measured")
    ax.plot(t, o.predicted, color="C3", lw=1.2, label="model")
    if after is not None:
        ax.plot(t, after.output(output).predicted, color="C0", lw=1.2, label="model + effect")
    ax.set_xlabel("t (s)")
    ax.set_ylabel(_label(o.name, o.unit))
    ax.set_title(f"{comparison.model}: {o.name}")
    ax.legend(loc="best")
    return ax


def residual(comparison: Comparison, output: str, ax: Optional[Axes] = None) -> Axes:
    """The residual (measured − model) with its band shaded and the failure windows
    highlighted and numbered."""
    ax = _axes(ax)
    o = comparison.output(output)
    t = comparison.t
    ax.axhspan(-o.band, o.band, color="C2", alpha=0.15, lw=0, label=f"band ±{o.band:.3g}")
    for k, (start, end, _peak) in enumerate(o.windows, start=1):
        ax.axvspan(start, end, color="C3", alpha=0.15, lw=0, label="fails" if k == 1 else None)
        ax.annotate(
            str(k),
            xy=(0.5 * (start + end), 1.0),
            xycoords=("data", "axes fraction"),
            ha="center",
            va="top",
        )
    ax.plot(t, o.residual, color="C3", lw=0.8, label="residual")
    ax.axhline(0.0, color="0.3", lw=0.5)
    ax.set_xlabel("t (s)")
    ax.set_ylabel(_label(f"{o.name} residual", o.unit))
    ax.legend(loc="best")
    return ax


def ranking(explanation: Explanation, ax: Optional[Axes] = None, top: int = 10) -> Axes:
    """The ranked candidates' scores as horizontal bars, the chosen ones highlighted."""
    ax = _axes(ax)
    ranked = [r for r in explanation.ranked if r.error is None][:top]
    chosen = {c.id for c in explanation.chosen}
    names = [r.name for r in ranked][::-1]
    scores = [max(r.score, 0.0) for r in ranked][::-1]
    colors: list[Any] = ["C0" if r.id in chosen else "0.7" for r in ranked][::-1]
    ax.barh(range(len(names)), scores, color=colors)
    ax.set_yticks(range(len(names)))
    ax.set_yticklabels(names)
    ax.set_xlabel("evidence (BIC difference)")
    ax.set_title(f"{explanation.model}: {explanation.verdict}")
    return ax


_AXIS = {"x": 0, "y": 1, "z": 2}


def _triangulation(u: Any, v: Any, triangles: Any) -> Any:
    from matplotlib.tri import Triangulation

    return Triangulation(u, v, triangles)


def cloth_error(
    vertices: npt.ArrayLike,
    triangles: npt.ArrayLike,
    error: npt.ArrayLike,
    ax: Optional[Axes] = None,
    *,
    ids: Optional[npt.ArrayLike] = None,
    view: str = "xy",
    cmap: str = "viridis",
    label: str = "error (m)",
) -> Axes:
    """The cloth error map: a per-vertex error coloured on the mesh.

    ``vertices`` ``(n, 3)`` (m) and ``triangles`` ``(m, 3)`` give the mesh (e.g.
    ``world.positions()`` and ``world.triangles()``), ``error`` one value per vertex, or one
    per vertex of ``ids`` (e.g. the ``(ids, rms)`` of ``cloth.marker_errors``). ``view``
    names the two world axes drawn (``"xy"``: a hanging cloth from the front, ``"xz"``:
    from above). With every vertex known the error is shaded over the triangles; with
    ``ids`` the mesh is drawn as a wireframe and the vertices as coloured dots. A colour bar
    labelled ``label`` is added.
    """
    if len(view) != 2 or view[0] not in _AXIS or view[1] not in _AXIS or view[0] == view[1]:
        raise ValueError(f'view must name two different axes of "x", "y", "z", found "{view}"')
    xyz = np.asarray(vertices, dtype=np.float64)
    tri = np.asarray(triangles)
    err = np.asarray(error, dtype=np.float64)
    if xyz.ndim != 2 or xyz.shape[1] != 3:
        raise ValueError(f"vertices must be (n, 3), found shape {xyz.shape}")
    if tri.ndim != 2 or tri.shape[1] != 3:
        raise ValueError(f"triangles must be (m, 3), found shape {tri.shape}")
    u, v = xyz[:, _AXIS[view[0]]], xyz[:, _AXIS[view[1]]]
    mappable: Any
    if ids is None:
        if err.shape != (len(xyz),):
            raise ValueError(
                f"error must hold one value per vertex ({len(xyz)},), found shape {err.shape}"
            )
        ax = _axes(ax)
        mappable = ax.tripcolor(_triangulation(u, v, tri), err, shading="gouraud", cmap=cmap)
    else:
        idx = np.asarray(ids, dtype=np.int64)
        if err.shape != idx.shape or idx.ndim != 1:
            raise ValueError(
                f"error must hold one value per id {idx.shape}, found shape {err.shape}"
            )
        if idx.size and (idx.min() < 0 or idx.max() >= len(xyz)):
            raise ValueError(f"ids must be vertex indices below {len(xyz)}")
        ax = _axes(ax)
        ax.triplot(_triangulation(u, v, tri), color="0.75", lw=0.4)
        mappable = ax.scatter(u[idx], v[idx], c=err, cmap=cmap, s=40, zorder=3)
    ax.figure.colorbar(mappable, ax=ax, label=label)
    ax.set_aspect("equal")
    ax.set_xlabel(f"{view[0]} (m)")
    ax.set_ylabel(f"{view[1]} (m)")
    return ax
