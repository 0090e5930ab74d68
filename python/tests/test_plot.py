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
