"""The measurement loop from Python, end to end, on the bundled DC-motor recording.

    pip install "./python[plot]"
    python examples/python/loop.py [OUT_DIR]

Loads the recording (a DC motor that hides a physical effect the built-in model lacks),
shows where the model fails, explains which effect is missing, adds it, shows the error
fall, and writes plots (PNG) and the HTML report into OUT_DIR (default ./modelgap-python/).
"""

from __future__ import annotations

import sys
from pathlib import Path

import modelgap
from modelgap.bond import BondModel

HERE = Path(__file__).resolve().parent
DATA = HERE.parent / "data" / "motor_hidden_effect.csv"


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("modelgap-python")
    out.mkdir(parents=True, exist_ok=True)

    rec = modelgap.Recording.load(DATA)
    motor = BondModel.dc_motor()
    print(f"recording: {rec!r}")
    print(f"model:     {motor!r}\n")

    before = modelgap.compare(motor, rec)
    print(before.text())

    explanation = modelgap.explain(
        motor, rec, progress=lambda done, total: print(f"\r  fitted {done}/{total}", end="")
    )
    print("\n")
    print(explanation.text(top=3))

    fixed = motor.with_effects(explanation.effects)
    after = modelgap.compare(fixed, rec)
    for b in before.outputs:
        a = after.output(b.name)
        print(
            f"{b.name:>6}: RMS {b.rms:.4g} -> {a.rms:.4g} {b.unit} (noise floor {b.noise_floor:.4g})"
        )

    (out / "dc-motor-fixed.toml").write_text(fixed.to_toml())
    page = modelgap.write_report(out / "report", before, explanation, after)

    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from modelgap import plot
    except ImportError:
        print("matplotlib is not installed: no PNG plots (pip install 'modelgap[plot]')")
    else:
        for name in ("i", "omega"):
            fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
            plot.measured_vs_model(before, name, ax=top, after=after)
            plot.residual(before, name, ax=bottom)
            fig.tight_layout()
            fig.savefig(out / f"{name}.png", dpi=120)
            plt.close(fig)
        fig, ax = plt.subplots(figsize=(8, 5))
        plot.ranking(explanation, ax=ax)
        fig.tight_layout()
        fig.savefig(out / "ranking.png", dpi=120)
        plt.close(fig)
    print(f"\nwrote {out}/: dc-motor-fixed.toml, i.png, omega.png, ranking.png; report {page}")


if __name__ == "__main__":
    main()
