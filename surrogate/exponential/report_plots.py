"""Fit-report plots (PNG, matplotlib Agg, imported only here): per family, FE curves
against the fitted models (like the paper's Figs. 3C and 4C), A against L and tau
against t (Figs. 3D and 4D) from the per-curve fits."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from surrogate.dataset import CurveData, select_angle_curves
from surrogate.exponential import equations
from surrogate.exponential.surrogate import Surrogate


def _slug(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", label).strip("_")


def write_report(s: Surrogate, curves: list[CurveData], out_dir: str | Path) -> list[Path]:
    """report.json (the surrogate's fit report) and the PNGs; returns the paths written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "report.json"]
    paths[0].write_text(json.dumps(s.report, indent=1, allow_nan=False), encoding="utf-8")
    angle_curves = select_angle_curves(curves)
    reports = {r["family"]: r for r in s.report.get("families", [])}
    for fam in s.family_fits:
        members = [c for c in angle_curves if fam.matches(c.design)]
        slug = _slug(fam.label)
        fig, ax = plt.subplots(figsize=(7, 5))
        colors = plt.cm.viridis(np.linspace(0, 0.9, max(len(members), 1)))
        for c, col in zip(sorted(members, key=lambda c: (c.design.t_mm, c.design.L_mm)),
                          colors, strict=False):
            p, y = c.usable_points()
            ax.plot(p, y, "o", ms=3, color=col,
                    label=f"FE L={c.design.L_mm:g} t={c.design.t_mm:g}")
            pp = np.linspace(0, p.max(), 100)
            for form, style in (("exponential", "--"), ("extended", ":")):
                if form in fam.parameters:
                    ax.plot(pp, equations.angle_deg(fam.parameters[form].theta, c.design.L_mm,
                                                c.design.t_mm, pp), style, color=col, lw=1)
        ax.set(xlabel="pressure (Pa)", ylabel="bending angle (deg)",
               title=f"{fam.label}\nFE (dots), paper form (--), extended (:)")
        if len(members) <= 12:
            ax.legend(fontsize=6)
        fig.tight_layout()
        paths.append(out / f"curves_{slug}.png")
        fig.savefig(paths[-1], dpi=120)
        plt.close(fig)
        rep = reports.get(fam.label)
        if rep is None:
            continue
        proc = rep["paper_procedure"]
        t4, t5 = proc["table_4"], proc["table_5"]
        theta = fam.parameters["exponential"].theta
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        L = np.array([r["L_mm"] for r in t4["rows"]])
        A = np.array([r["A_deg"] for r in t4["rows"]])
        axes[0].plot(L, A, "o", label=f"tau fixed at {t4['tau_fixed_pa']:.0f} Pa")
        if "length_constant" in t4 and len(L):
            Lg = np.linspace(0, L.max() * 1.05, 50)
            axes[0].plot(Lg, t4["length_constant"]["a_deg_per_mm"] * Lg, "-",
                         label="A = a L (through the origin)")
        axes[0].set(xlabel="chamber length L (mm)", ylabel="A (deg)",
                    title=f"A vs L at t = {t4['t_mm']:g} mm")
        axes[0].legend(fontsize=7)
        t = np.array([r["t_mm"] for r in t5["rows"]])
        tau = np.array([r["tau_pa"] for r in t5["rows"]])
        axes[1].plot(t, tau, "o", label=f"A fixed at {t5['A_fixed_deg']:.3g} deg")
        tg = np.linspace(max(t.min() * 0.8, 1.01 / theta[2]), t.max() * 1.1, 50) if len(t) \
            else np.array([])
        if "thickness_constants" in t5 and len(t):
            tc = t5["thickness_constants"]
            axes[1].plot(tg, equations.tau_from_constants(tc["a_t_pa"], tc["b_t_per_mm"], tg), "-",
                         label="tau = a_t log10(b_t t)")
        if len(tg):
            axes[1].plot(tg, equations.tau_pa(theta, tg), ":", label="joint fit")
        axes[1].set(xlabel="membrane thickness t (mm)", ylabel="tau (Pa)",
                    title=f"tau vs t at L = {t5['L_mm']:g} mm")
        axes[1].legend(fontsize=7)
        fig.tight_layout()
        paths.append(out / f"constants_{slug}.png")
        fig.savefig(paths[-1], dpi=120)
        plt.close(fig)
    return paths
