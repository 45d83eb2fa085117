"""The calibration plot: data with the model before and after, and both residuals."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_calibration(cal, path: str | Path) -> Path:
    """Write a PNG: left, angle against gauge pressure (points: data; dashed: recalibrated
    baseline; solid: after the selected effects; lines in the order the readings were
    taken, so loading/unloading loops and holds show); right, out-of-fold residuals (each
    curve predicted by a fit that did not see it) before and after, with the noise floor
    band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    obs, r = cal.obs, cal.report
    before = cal.before.angles()
    after = cal.after.angles()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8))
    cmap = plt.get_cmap("tab10")
    groups = np.unique(obs.group)
    for gi, g in enumerate(groups):
        color = cmap(gi % 10)
        for c in np.unique(obs.curve[obs.group == g]):
            rows = np.flatnonzero(obs.curve == c)
            k = rows  # history order
            ax.plot(obs.pressure_pa[k], obs.angle_deg[k], "o", ms=3, color=color)
            ax.plot(obs.pressure_pa[k], before[k], "--", lw=0.8, color=color)
            ax.plot(obs.pressure_pa[k], after[k], "-", lw=1.2, color=color)
        d = obs.curve_design(int(obs.curve[obs.group == g][0]))
        ax.plot([], [], "o-", color=color, label=f"L {d['L_mm']:g}, t {d['t_mm']:g} mm"
                + (f", {d['flow_ul_s']:g} ul/s" if d["flow_ul_s"] == d["flow_ul_s"] else ""))
    out = [q for q in r.get("predictions") or () if q.get("left_out")]
    if out:     # past the nominal design's FE range: not in the fit, predicted after it
        ax.plot([q["pressure_pa"] for q in out], [q["angle_deg"] for q in out], "o", ms=4,
                mfc="none", color="0.45", label=f"left out of the fit ({len(out)}: past the "
                "nominal design's FE range)")
        ax.plot([q["pressure_pa"] for q in out],
                [np.nan if q["angle_after_deg"] is None else q["angle_after_deg"]
                 for q in out], "x", ms=4, color="0.2",
                label="their prediction after the fit")
    ax.plot([], [], "k--", lw=0.8, label=f"baseline {r['baseline']['name']} (recalibrated)")
    ax.plot([], [], "k-", lw=1.2, label="after: " + (", ".join(r["selected_effects"]) or
                                                       "no effect"))
    ax.set_xlabel("gauge pressure (Pa)")
    ax.set_ylabel("bending angle (deg)")
    ax.legend(fontsize=7)
    ax.set_title("data and model")
    noise = r["noise_floor_deg"] or 0.0
    bx.axhspan(-noise, noise, color="0.9", label=f"noise floor +/- {noise:.2f} deg")
    bx.plot(obs.pressure_pa, cal.residual_before_cv, ".", color="tab:red", ms=4,
            label=f"before: {r['rmse_before_deg']:.2f} deg RMS (CV)")
    bx.plot(obs.pressure_pa, cal.residual_after_cv, ".", color="tab:blue", ms=4,
            label=f"after: {r['rmse_after_deg']:.2f} deg RMS (CV)")
    bx.axhline(0.0, color="k", lw=0.5)
    bx.set_xlabel("gauge pressure (Pa)")
    bx.set_ylabel("model - data, out of fold (deg)")
    title = "residuals" + (" -- structure remains" if r["residual_structured_after"] else "")
    bx.set_title(title)
    bx.legend(fontsize=7)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
