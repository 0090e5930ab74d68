"""modelgap.plot draws on Axes and returns them (skipped without matplotlib)."""

from __future__ import annotations

import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

import modelgap  # noqa: E402
from modelgap import plot  # noqa: E402
from modelgap.bond import BondModel, hidden_recording  # noqa: E402


@pytest.fixture(scope="module")
def loop():
    rec = hidden_recording("load", seed=1, duration=2.0)
    motor = BondModel.dc_motor()
    ex = modelgap.explain(motor, rec, only=["load@1m", "coulomb@1m", "deviation:R"])
    before = modelgap.compare(motor, rec)
    after = modelgap.compare(motor.with_effects(ex.effects), rec)
    return before, ex, after


def test_measured_vs_model(loop):
    before, _, after = loop
    ax = plot.measured_vs_model(before, "omega", after=after)
    assert len(ax.lines) == 3
    plt.close(ax.figure)


def test_residual_shades_band_and_windows(loop):
    before, _, _ = loop
    fig, ax = plt.subplots()
    assert plot.residual(before, "omega", ax=ax) is ax
    assert len(ax.patches) >= 1 + len(before.output("omega").windows)
    plt.close(fig)


def test_ranking(loop):
    _, ex, _ = loop
    ax = plot.ranking(ex)
    assert len(ax.patches) == 3
    plt.close(ax.figure)


def test_cloth_error_map_on_the_mesh():
    import numpy as np

    from modelgap import cloth

    world = cloth.ClothWorld()
    c = world.add_cloth(cloth.ClothMesh.grid(5, 5, 0.1, pins=[0]))
    world.step(10, dt=0.01)
    x, tri = world.positions(c), world.triangles(c)
    error = np.linalg.norm(x - x[0], axis=1)  # any per-vertex value
    fig, ax = plt.subplots()
    assert plot.cloth_error(x, tri, error, ax=ax, view="xy") is ax
    assert len(ax.collections) == 1  # the shaded mesh
    assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)"
    assert len(fig.axes) == 2  # and its colour bar
    plt.close(fig)
    ax = plot.cloth_error(x, tri, error[[3, 24]], ids=[3, 24], view="xz")
    assert len(ax.lines) >= 1 and len(ax.collections) == 1  # wireframe and two dots
    assert ax.collections[0].get_offsets().shape == (2, 2)
    plt.close(ax.figure)
    with pytest.raises(ValueError, match="view must name two different axes"):
        plot.cloth_error(x, tri, error, view="xx")
    with pytest.raises(ValueError, match=r"error must hold one value per vertex \(25,\)"):
        plot.cloth_error(x, tri, error[:3])
    plt.close("all")
