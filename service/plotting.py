"""The PNG of /v1/predict/plot: predicted curve and band, nearby FE curves, measurements."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np


def nearby_curves(db_path: Path, design: Any, count: int, p_max_pa: float
                  ) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Up to ``count`` converged FE curves of the design's family, nearest in (L, t) first,
    as (label, pressure_pa, angle_deg); empty when there is no database."""
    from service.store_access import open_store

    if count == 0 or not Path(db_path).is_file():
        return []
    family = design.family
    with open_store(db_path) as db:
        rows = []
        for row in db.summaries():
            d = row["design"]
            same = (d["body_material"], d["membrane_material"], round(d["T_mm"], 6),
                    round(d["b_mm"], 6), round(d["h_mm"], 6)) == family
            if same and row["status"] != "failed":
                distance = np.hypot((d["L_mm"] - design.L_mm) / 10.0,
                                    (d["t_mm"] - design.t_mm) / 0.5)
                rows.append((distance, str(row["key"])))
        rows.sort()
        records = [db.get(key) for _, key in rows[:count]]
    out = []
    for record in records:
        c, d = record.curve, record.design
        keep = np.asarray(c.pressure_pa) <= p_max_pa * 1.05
        out.append((f"FE L={d.L_mm:g} mm, t={d.t_mm:g} mm",
                    np.asarray(c.pressure_pa)[keep], np.asarray(c.angle_deg)[keep]))
    return out


def plot_prediction(prediction: dict[str, Any],
                    fe_curves: list[tuple[str, np.ndarray, np.ndarray]],
                    measured_pressure_pa: list[float], measured_angle_deg: list[float]
                    ) -> bytes:
    """Angle (degrees) against pressure (Pa) as PNG bytes (Agg; no pyplot, thread-safe)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.0, 4.0), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    p = np.asarray(prediction["pressure_pa"], float)
    nan = float("nan")

    def arr(key: str) -> np.ndarray:
        return np.array([nan if v is None else v for v in prediction[key]], float)

    ax.fill_between(p, arr("lower_deg"), arr("upper_deg"), alpha=0.25, color="C0",
                    label=f"{100 * prediction['level']:.0f} % band")
    ax.plot(p, arr("angle_deg"), color="C0", lw=2, label=f"model {prediction['model']}")
    for i, (label, fp, fa) in enumerate(fe_curves):
        ax.plot(fp, fa, color=f"C{i + 1}", lw=1, ls="--", label=label)
    if measured_pressure_pa:
        ax.plot(measured_pressure_pa, measured_angle_deg, "ko", ms=4, label="measured")
    d = prediction["design"]
    ax.set_title(f"L = {d['L_mm']:g} mm, t = {d['t_mm']:g} mm, "
                 f"{d['body_material']['id']} / {d['membrane_material']['id']}", fontsize=10)
    if not prediction["validity"]["in_domain"]:
        ax.text(0.02, 0.95, "outside the fitted domain", transform=ax.transAxes,
                color="C3", va="top", fontsize=9)
    ax.set_xlabel("pressure (Pa)")
    ax.set_ylabel("bending angle (deg)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()
