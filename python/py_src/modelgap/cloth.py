"""Impulse-based simulation of inextensible cloth (Bender & Bayer) from Python.

Build a mesh (``ClothMesh.grid``, ``ClothMesh(vertices, triangles)`` from numpy arrays, or
``ClothMesh.load_obj``), add it to a ``ClothWorld`` with colliders and solver parameters,
and step it; or start from a reference scene::

    from modelgap import cloth

    mesh = cloth.ClothMesh.grid(10, 10, 0.05, pins=[0, 9])
    world = cloth.ClothWorld(cloth.SolverParams(stretch_tolerance=1e-4))
    c = world.add_cloth(mesh)
    world.add_collider(cloth.Collider.ball((0.2, -0.3, 0.2), 0.1, friction=0.3))
    report = world.step(100, dt=0.01)      # StepReport: iterations, max_stretch, converged
    xyz = world.positions(c)               # a fresh (100, 3) float64 array

    scene = cloth.scene("corner").resized(10, 10)
    run = scene.run(duration=0.5)          # frames, markers (a MarkerRecording), stats

Markers (the positions of chosen vertices over time) are ``MarkerRecording`` objects, read
and written as CSV (``t,id,x,y,z``) or MCAP. The measurement loop works on cloth too: a
``ClothModel`` (a scene) is held against ``markers.to_recording()`` by ``modelgap.compare``,
``modelgap.explain`` names the effect it misses (drag, wind, damping, bending, stretch,
mass, a point mass, friction) and ``model.with_effects(ex.effects)`` adds it.
"""

from __future__ import annotations

import re

import numpy as np
import numpy.typing as npt

from ._modelgap import (
    Comparison,
    ClothMesh,
    ClothModel,
    ClothRun,
    ClothWorld,
    Collider,
    MarkerRecording,
    Scene,
    SolverParams,
    StepReport,
    scene,
    scenes,
)

__all__ = [
    "ClothMesh",
    "ClothModel",
    "ClothRun",
    "ClothWorld",
    "Collider",
    "MarkerRecording",
    "Scene",
    "SolverParams",
    "StepReport",
    "marker_errors",
    "vertex_errors",
    "scene",
    "scenes",
]


def marker_errors(
    model: MarkerRecording, measured: MarkerRecording
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """The RMS distance (m) between two marker recordings, marker by marker.

    Both must have the same frame times (within 1 ns); markers are matched by id, and only
    ids in both count. Returns ``(ids, rms)``: the shared ids in ``measured``'s order and
    each one's root-mean-square distance over the frames, ready for
    ``modelgap.plot.cloth_error``.
    """
    t_model, ids_model, x_model = model.to_numpy()
    t_meas, ids_meas, x_meas = measured.to_numpy()
    if t_model.shape != t_meas.shape or not np.allclose(t_model, t_meas, rtol=0.0, atol=1e-9):
        raise ValueError(
            f"the recordings must share their frame times: {len(t_model)} frames "
            f"({t_model[0]}..{t_model[-1]} s) vs {len(t_meas)} frames "
            f"({t_meas[0]}..{t_meas[-1]} s)"
        )
    where = {int(i): k for k, i in enumerate(ids_model)}
    shared = [k for k, i in enumerate(ids_meas) if int(i) in where]
    if not shared:
        raise ValueError("the recordings share no marker id")
    ids = ids_meas[shared]
    a = x_model[:, [where[int(i)] for i in ids], :]
    b = x_meas[:, shared, :]
    rms = np.sqrt(np.mean(np.sum((a - b) ** 2, axis=2), axis=0))
    return ids, rms


_MARKER_SIGNAL = re.compile(r"^m(\d+)\.([xyz])$")


def vertex_errors(
    comparison: Comparison,
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """The RMS distance (m) between model and markers, vertex by vertex, from a
    ``Comparison`` of a ``ClothModel``: ``sqrt(rms_x² + rms_y² + rms_z²)`` over the marker
    signals ``m{id}.x|y|z`` it compared (an axis not compared counts as 0).

    Returns ``(ids, rms)``, ids ascending, ready for ``modelgap.plot.cloth_error``.
    """
    squares: dict[int, float] = {}
    for o in comparison.outputs:
        m = _MARKER_SIGNAL.match(o.name)
        if m is None:
            continue
        vertex = int(m.group(1))
        squares[vertex] = squares.get(vertex, 0.0) + o.rms**2
    if not squares:
        raise ValueError(
            f"the comparison of {comparison.model!r} holds no marker signal m{{id}}.x|y|z"
        )
    ids = np.array(sorted(squares), dtype=np.int64)
    return ids, np.sqrt(np.array([squares[int(i)] for i in ids]))
