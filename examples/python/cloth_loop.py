"""The measurement loop on cloth, from Python, end to end.

    pip install "./python[plot]"
    python examples/python/cloth_loop.py [OUT_DIR]

A small cloth (6 x 6 vertices, 1 m square) hangs from one corner. The "measurement" is a
recording of four markers on the same cloth falling through air (drag the model does not
have), with 1 mm of sensor noise. The loop shows where the model fails, names the missing
effect, adds it and shows the error fall; plots (PNG), the fixed scene file and the markers
(CSV) go to OUT_DIR (default ./modelgap-cloth/).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import modelgap
from modelgap import cloth

# The hidden effect: aerodynamic drag on the cloth's triangles (C_d, dimensionless).
DRAG_COEFFICIENT = 0.5
NOISE = 1e-3  # m, the markers' sensor noise (standard deviation)
MARKERS = [5, 21, 30, 35]  # vertex ids (row * 6 + col): two corners, the middle, the far corner
T = np.arange(101) * 0.01  # s, one second at 100 Hz


def measured_markers(model: cloth.ClothModel) -> cloth.MarkerRecording:
    """The model's scene with drag added, at the marker vertices, plus sensor noise."""
    truth_text = model.scene.to_toml() + f"\n[air]\ndrag_coefficient = {DRAG_COEFFICIENT}\n"
    truth = cloth.ClothModel(cloth.Scene.from_toml(truth_text, "truth"))
    clean = truth.simulate(T, ids=MARKERS)
    rng = np.random.default_rng(1)
    positions = clean.positions + rng.normal(0.0, NOISE, clean.positions.shape)
    return cloth.MarkerRecording(T, clean.ids, positions)


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("modelgap-cloth")
    out.mkdir(parents=True, exist_ok=True)

    model = cloth.ClothModel.from_scene("corner", nx=6, nz=6)
    markers = measured_markers(model)
    markers.save(out / "markers.csv")
    rec = markers.to_recording()
    print(f"model:   {model!r}")
    print(f"markers: {markers!r}\n")

    before = modelgap.compare(model, rec)
    ids, err_before = cloth.vertex_errors(before)
    for i, e in zip(ids, err_before):
        print(f"marker {i:>2}: the model is {e * 1e3:7.1f} mm off (RMS over the second)")

    explanation = modelgap.explain(model, rec)
    print(f"\nverdict: {explanation.verdict}")
    for c in explanation.chosen:
        values = ", ".join(
            f"{p.name} = {p.value:.4g} ± {p.std_error:.2g} {p.unit}" for p in c.params
        )
        print(f"missing: {c.name} ({values})")
    print("runners-up: " + ", ".join(f"{r.id} ({r.score:.3g})" for r in explanation.ranked[1:4]))

    fixed = model.with_effects(explanation.effects)
    after = modelgap.compare(fixed, rec)
    _, err_after = cloth.vertex_errors(after)
    print(
        f"\nRMS over the markers: {np.sqrt(np.mean(err_before**2)) * 1e3:.1f} mm -> "
        f"{np.sqrt(np.mean(err_after**2)) * 1e3:.2f} mm (noise {NOISE * 1e3:.1f} mm per axis)"
    )
    (out / "corner-fixed.toml").write_text(fixed.to_toml())
    # What the missing effect does to every vertex: the model as given against the fixed one.
    _, effect = cloth.marker_errors(model.simulate(T), fixed.simulate(T))

    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from modelgap import plot
    except ImportError:
        print("matplotlib is not installed: no PNG plots (pip install 'modelgap[plot]')")
    else:
        # The cloth at the end of the recording, seen from the side (x-y): the markers coloured
        # by the model's error, and every vertex by how far the missing drag moves it.
        last = fixed.simulate(T[-1:]).positions[0]
        triangles = model.scene.mesh().triangles
        fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
        plot.cloth_error(last, triangles, err_before, ids=ids, ax=left, label="RMS error (m)")
        left.set_title("markers: model as given vs measured")
        plot.cloth_error(last, triangles, effect, ax=right, label="RMS displacement (m)")
        right.set_title("what " + " + ".join(c.id for c in explanation.chosen) + " moves")
        fig.tight_layout()
        fig.savefig(out / "cloth-error.png", dpi=120)
        plt.close(fig)
        far = f"m{int(ids[-1])}.y"
        fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
        plot.measured_vs_model(before, far, ax=top, after=after)
        plot.residual(before, far, ax=bottom)
        fig.tight_layout()
        fig.savefig(out / "far-corner.png", dpi=120)
        plt.close(fig)
    print(f"\nwrote {out}/: markers.csv, corner-fixed.toml, cloth-error.png, far-corner.png")


if __name__ == "__main__":
    main()
