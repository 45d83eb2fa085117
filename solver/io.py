"""Thin file outputs of a Curve: CSV and a PNG plot."""

from __future__ import annotations

import csv

import numpy as np

from solver.curve import Curve

CSV_COLUMNS = ("pressure_pa", "volume_ul", "time_s", "angle_deg", "tip_dx_mm", "tip_dz_mm",
               "max_membrane_stretch", "force_mn", "newton_iterations", "residual_norm",
               "negative_eigenvalues")


def curve_rows(curve: Curve) -> list[list[float]]:
    tip = np.asarray(curve.tip_displacement_mm)
    cols = [curve.pressure_pa, curve.volume_ul, curve.time_s, curve.angle_deg, tip[:, 0],
            tip[:, 1], curve.max_membrane_stretch, curve.force_mn, curve.newton_iterations,
            curve.residual_norm, curve.negative_eigenvalues]
    return [[float(c[i]) for c in cols] for i in range(len(curve))]


def curve_to_csv(curve: Curve, path: str) -> None:
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(CSV_COLUMNS)
        writer.writerows(curve_rows(curve))


def plot_curve(curve: Curve, path: str, title: str = "") -> None:
    """Angle and injected volume against pressure (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.6))
    ax1.plot(curve.pressure_pa, curve.angle_deg, "o-", ms=3)
    ax1.set_xlabel("pressure (Pa)")
    ax1.set_ylabel("bending angle (deg)")
    ax1.grid(alpha=0.3)
    ax2.plot(curve.volume_ul, curve.pressure_pa, "o-", ms=3, color="C1")
    ax2.set_xlabel("injected volume (ul)")
    ax2.set_ylabel("pressure (Pa)")
    ax2.grid(alpha=0.3)
    if curve.pressure_maximum_index >= 0:
        i = curve.pressure_maximum_index
        ax2.plot(curve.volume_ul[i], curve.pressure_pa[i], "rv", label="pressure maximum")
        ax2.legend()
    fig.suptitle(f"{title}  [{curve.status}]")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
