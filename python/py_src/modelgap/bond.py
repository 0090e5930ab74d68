"""Bond-graph models: load, inspect (equations, state space, causal graph, fault trees,
ARRs), simulate and diagnose; they are what ``modelgap.compare`` and ``modelgap.explain``
take.

``BondModel.dc_motor()`` is the DC motor of the fault-diagnosis paper; ``table7()`` runs
its Table 7; ``hidden_recording(case)`` makes a recording of a motor with a hidden effect.
"""

from __future__ import annotations

from ._modelgap import BondModel, Diagnosis, hidden_cases, hidden_recording, table7

__all__ = ["BondModel", "Diagnosis", "hidden_cases", "hidden_recording", "table7"]
