"""The PNGs of /v1/predict/plot: predicted curve and band, nearby FE curves, measurements;
against pressure, or against time at a flow rate with the pressure on a second axis."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np


def nearby_records(db_path: Path, design: Any, count: int) -> list[Any]:
    """Up to ``count`` converged FE records of the design's family, nearest in (L, t)
    first; empty when there is no database."""
    from service.store_access import file_version, open_store, summary_rows

    if count == 0 or not Path(db_path).is_file():
        return []
    family = design.family
    try:
        version = file_version(Path(db_path))
    except OSError:         # gone since: no nearby curves, as without a database
        return []
    with open_store(db_path) as db:
        rows = []
        for row in summary_rows(version, db):
            d = row["design"]
            same = (d["body_material"], d["membrane_material"], round(d["T_mm"], 6),
                    round(d["b_mm"], 6), round(d["h_mm"], 6)) == family
            if same and row["status"] != "failed":
                distance = np.hypot((d["L_mm"] - design.L_mm) / 10.0,
                                    (d["t_mm"] - design.t_mm) / 0.5)
                rows.append((distance, str(row["key"])))
        rows.sort()
        return [db.get(key) for _, key in rows[:count]]


def nearby_curves(db_path: Path, design: Any, count: int, x_max: float,
                  flow_ul_s: float | None = None) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The ``nearby_records`` as (label, x, angle_deg) up to 1.05 ``x_max``: x the
    pressure (Pa), or at ``flow_ul_s`` the time (s), each record's own injected volume
    over the flow rate."""
    out = []
    for record in nearby_records(db_path, design, count):
        c = record.curve
        x = (np.asarray(c.pressure_pa) if flow_ul_s is None
             else np.asarray(c.volume_ul) / flow_ul_s)
        keep = x <= x_max * 1.05
        out.append((f"FE L={record.design.L_mm:g} mm, t={record.design.t_mm:g} mm",
                    x[keep], np.asarray(c.angle_deg)[keep]))
    return out


def _figure() -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.0, 4.0), dpi=100)
    FigureCanvasAgg(fig)
    return fig


def _png(fig: Any) -> bytes:
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def _values(prediction: dict[str, Any], key: str) -> np.ndarray:
    """A response list as floats (null -> NaN: a gap in the line)."""
    return np.array([np.nan if v is None else v for v in prediction[key]], float)


def _title(ax: Any, prediction: dict[str, Any], extra: str = "") -> None:
    d = prediction["design"]
    ax.set_title(f"L = {d['L_mm']:g} mm, t = {d['t_mm']:g} mm, "
                 f"{d['body_material']['id']} / {d['membrane_material']['id']}{extra}",
                 fontsize=10)
    if not prediction["validity"]["in_domain"]:
        ax.text(0.02, 0.95, "outside the fitted domain", transform=ax.transAxes,
                color="C3", va="top", fontsize=9)


def _draw_angles(ax: Any, prediction: dict[str, Any], x_key: str,
                 fe_curves: list[tuple[str, np.ndarray, np.ndarray]],
                 first_fe_color: int) -> np.ndarray:
    """The answer's angle and band against ``x_key``, and the FE curves dashed; returns x."""
    x = _values(prediction, x_key)
    ax.fill_between(x, _values(prediction, "lower_deg"), _values(prediction, "upper_deg"),
                    alpha=0.25, color="C0", label=f"{100 * prediction['level']:.0f} % band")
    ax.plot(x, _values(prediction, "angle_deg"), color="C0", lw=2,
            label=f"model {prediction['model']}")
    for i, (label, fx, fa) in enumerate(fe_curves):
        ax.plot(fx, fa, color=f"C{i + first_fe_color}", lw=1, ls="--", label=label)
    return x


def plot_in_time(prediction: dict[str, Any],
                 fe_curves: list[tuple[str, np.ndarray, np.ndarray]]) -> bytes:
    """The paper's protocol as PNG bytes: angle (deg) with its band against time (s) at
    the answer's flow rate, and on a second axis the chamber pressure (and the pump
    gauge's when the answer has it), Pa."""
    fig = _figure()
    ax = fig.add_subplot()
    t = _draw_angles(ax, prediction, "time_s", fe_curves, first_fe_color=2)
    ax.set_xlabel(f"time at {prediction['flow_ul_s']:g} ul/s (s)")
    ax.set_ylabel("bending angle (deg)")
    ax.grid(alpha=0.3)
    right = ax.twinx()
    right.plot(t, _values(prediction, "pressure_pa"), color="C1", lw=1.5,
               label="chamber pressure")
    if prediction.get("pump_pressure_pa"):
        right.plot(t, _values(prediction, "pump_pressure_pa"), color="C1", lw=1.2, ls=":",
                   label="pump gauge (+ R Q)")
    right.set_ylabel("pressure (Pa)", color="C1")
    right.tick_params(axis="y", colors="C1")
    _title(ax, prediction, f", {prediction['flow_ul_s']:g} ul/s")
    lines = ax.get_legend_handles_labels()
    more = right.get_legend_handles_labels()
    ax.legend(lines[0] + more[0], lines[1] + more[1], fontsize=8, loc="upper left")
    return _png(fig)


def plot_prediction(prediction: dict[str, Any],
                    fe_curves: list[tuple[str, np.ndarray, np.ndarray]],
                    measured_pressure_pa: list[float], measured_angle_deg: list[float]
                    ) -> bytes:
    """Angle (degrees) against pressure (Pa) as PNG bytes (Agg; no pyplot, thread-safe)."""
    fig = _figure()
    ax = fig.add_subplot()
    _draw_angles(ax, prediction, "pressure_pa", fe_curves, first_fe_color=1)
    if measured_pressure_pa:
        ax.plot(measured_pressure_pa, measured_angle_deg, "ko", ms=4, label="measured")
    _title(ax, prediction)
    ax.set_xlabel("pressure (Pa)")
    ax.set_ylabel("bending angle (deg)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    return _png(fig)
