"""The PNGs of /v1/predict/plot: predicted curve and band, nearby FE curves, measurements;
against pressure, or against time at a flow rate with the pressure on a second axis."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

# Solver settings that change a stored curve, and how a label names a value other than
# the default's (SolverSettings()): a coarse or truncated run is not read as "the FE".
SETTING_WORDS = {"element": "{}", "mesh_level": "mesh level {}",
                 "mesh_divisions": "{} mesh", "control": "{} control",
                 "max_angle_deg": "stopped at {:g} deg", "max_pressure_pa": "stopped at {:g} Pa",
                 "max_volume_ul": "stopped at {:g} ul", "tip": "{} tip"}


def settings_note(settings: dict[str, Any]) -> str:
    """The settings of a stored FE record that differ from the default solve, in words
    (``"hex1, stopped at 10 deg"``); empty for a default run."""
    from solver.settings import SolverSettings

    default = SolverSettings()
    return ", ".join(words.format(settings[name]) for name, words in SETTING_WORDS.items()
                     if name in settings and settings[name] != getattr(default, name))


def _family_at_3mm(d: dict[str, Any]) -> tuple[Any, ...]:
    """A design's family (materials, T, b, h) with its lengths scaled to W = 3 mm: angle
    against pressure is the same for every scaled copy (docs/physics.md)."""
    k = d["W_mm"] / 3.0
    return (d["body_material"], d["membrane_material"],
            *(round(d[n] / k, 6) for n in ("T_mm", "b_mm", "h_mm")))


def nearby_records(db_path: Path, design: Any, count: int) -> list[Any]:
    """Up to ``count`` converged free-tip FE records of the design's family (its scaled
    copies too: lengths compared at W = 3 mm), nearest in (L, t) first; empty when there
    is no database. A blocked or sprung tip's angle is not the free tip's: left out."""
    from service.store_access import file_version, open_store, summary_rows

    if count == 0 or not Path(db_path).is_file():
        return []
    mine = {"body_material": design.body_material.id,
            "membrane_material": design.membrane_material.id,
            **{n: getattr(design, n) for n in ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm",
                                               "W_mm")}}
    family, k = _family_at_3mm(mine), design.W_mm / 3.0
    try:
        version = file_version(Path(db_path))
    except OSError:         # gone since: no nearby curves, as without a database
        return []
    with open_store(db_path) as db:
        rows = []
        for row in summary_rows(version, db):
            d = row["design"]
            if (_family_at_3mm(d) == family and row["status"] != "failed"
                    and row["settings"].get("tip", "free") == "free"):
                kd = d["W_mm"] / 3.0
                distance = np.hypot((d["L_mm"] / kd - design.L_mm / k) / 10.0,
                                    (d["t_mm"] / kd - design.t_mm / k) / 0.5)
                rows.append((distance, str(row["key"])))
        rows.sort()
        return [db.get(key) for _, key in rows[:count]]


def nearby_curves(db_path: Path, design: Any, count: int, x_max: float,
                  flow_ul_s: float | None = None) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The ``nearby_records`` as (label, x, angle_deg) up to 1.05 ``x_max``: x the
    pressure (Pa), or at ``flow_ul_s`` the time (s), each record's own injected volume
    (scaled to the design's width, x k^3) over the flow rate. The label names the
    record's lengths, its width when not the design's, and its solver settings where they
    are not the default solve's (``settings_note``)."""
    out = []
    for record in nearby_records(db_path, design, count):
        c, rd = record.curve, record.design
        k3 = (design.W_mm / rd.W_mm) ** 3
        x = (np.asarray(c.pressure_pa) if flow_ul_s is None
             else k3 * np.asarray(c.volume_ul) / flow_ul_s)
        keep = x <= x_max * 1.05
        label = f"FE L={rd.L_mm:g} mm, t={rd.t_mm:g} mm"
        if rd.W_mm != design.W_mm:
            label += f", W={rd.W_mm:g} mm"
        note = settings_note(record.settings.as_dict())
        out.append((label + (f" ({note})" if note else ""), x[keep],
                    np.asarray(c.angle_deg)[keep]))
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
    """The design in full (every length, the width, the pair) over the plot; a third line
    when the design is outside the model's domain (``validity.in_domain``), in the title
    so that it never covers the legend or a curve."""
    d = prediction["design"]
    lines = [", ".join(f"{n} = {d[f'{n}_mm']:g}" for n in ("L", "t", "T", "b", "h", "W"))
             + " mm",
             f"{d['body_material']['id']} / {d['membrane_material']['id']}{extra}"]
    validity = prediction["validity"]
    if not validity["in_domain"]:
        from surrogate.predictor import NOT_ABOUT_THE_DESIGN

        lines.append("outside the model's fitted domain: " + ", ".join(
            f for f in validity["flags"] if f not in NOT_ABOUT_THE_DESIGN))
    ax.set_title("\n".join(lines), fontsize=9)


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
    # below the axes: "best" sees only the angle axis, and covered the pressure curves
    ax.legend(lines[0] + more[0], lines[1] + more[1], fontsize=7, ncol=2,
              loc="upper center", bbox_to_anchor=(0.5, -0.17))
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
    ax.legend(fontsize=7, loc="best")   # where it covers the fewest points
    return _png(fig)
