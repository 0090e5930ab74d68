"""Shared fixtures: short numpy signals, the DC motor, a recording of it."""

from __future__ import annotations

import numpy as np
import pytest

import modelgap
from modelgap.bond import BondModel


@pytest.fixture
def signals() -> tuple[np.ndarray, np.ndarray, list[str]]:
    t = np.linspace(0.0, 1.0, 101)
    values = np.column_stack([np.sin(t), np.cos(t), t**2])
    return t, values, ["a", "b", "c"]


@pytest.fixture
def motor() -> BondModel:
    return BondModel.dc_motor()


@pytest.fixture
def motor_run(motor: BondModel) -> modelgap.Recording:
    """Half a second of the DC motor from rest at its default 12 V."""
    t = np.linspace(0.0, 0.5, 501)
    return motor.simulate(t)
