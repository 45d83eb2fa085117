"""The emulator against held-out FE curves, and its query time.

    python benchmarks/heldout_designs.py --n 16 --seed 2026 --db heldout.h5 --blocked 4
    python benchmarks/bench_emulator.py --heldout heldout.h5 [--emulator service/data/emulator.json]

For every held-out curve (random designs inside the box, not in the database, solved by
the default FE): the emulator at the FE's own pressures up to 90 deg, and at its own
injected volumes (the syringe-pump view, ``--axis``) -- RMSE, max error and the share of
FE points inside the 95 % band; a curve whose Newton iteration failed is scored over its
converged part, and its own summary line says how those fared; a refusal (near the
Ecoflex/Ecoflex balance, or too few curves) is counted as such. Blocked-tip held-out
curves are compared in force (mN) within the emulator's force range. Query time: 100
pressures with bands, median of 2000 calls, next to the exponential model's in the same
run (a ratio).
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass, field

import numpy as np

from solver.design_space import locate
from solver.errors import InputError
from solver.store import CurveStore
from surrogate import load_surrogate
from surrogate.emulator import force_answer as force_answer_module
from surrogate.emulator import load_emulator
from surrogate.emulator.band_scales import ANGLE_BINS_DEG, angle_bin


@dataclass
class HeldOut:
    """Errors of one emulator on held-out FE curves (deg for angle, mN for force)."""

    axis: str
    lines: list[str] = field(default_factory=list)
    curve_rmse_deg: list[float] = field(default_factory=list)
    curve_max_deg: list[float] = field(default_factory=list)
    errors_deg: list[np.ndarray] = field(default_factory=list)
    inside: int = 0
    total: int = 0
    refused: int = 0
    unanswered: int = 0                 # curves past the emulated range at every point
    force_errors_mn: list[np.ndarray] = field(default_factory=list)
    force_inside: int = 0
    force_total: int = 0
    force_withheld: int = 0
    force_answered: int = 0             # points the answer gives (band within the limit)
    force_answered_inside: int = 0
    fe_deg: list[np.ndarray] = field(default_factory=list)
    inside_points: list[np.ndarray] = field(default_factory=list)
    near_failed: list[bool] = field(default_factory=list)   # flag near_early_ended_fe_curves
    undercover: list[bool] = field(default_factory=list)    # band_undercovers_random_designs
    ended_early: list[bool] = field(default_factory=list)   # the FE curve stops short of 90 deg
    fe_failed: list[bool] = field(default_factory=list)     # a Newton failure: its converged part

    def summary(self) -> str:
        flat = np.concatenate(self.errors_deg) if self.errors_deg else np.array([np.nan])
        both = sum(r <= 1 and m <= 3 for r, m in zip(self.curve_rmse_deg, self.curve_max_deg))
        text = ("no free-tip curves" if not self.errors_deg and not self.refused else
                f"all {len(self.errors_deg)} answered curves ({self.total} points, "
                f"{self.refused} refused), by {self.axis}: rmse "
                f"{np.sqrt(np.mean(flat**2)):.2f} deg, max {np.nanmax(np.abs(flat)):.2f} deg, "
                f"95 % band coverage {self.inside / max(self.total, 1):.3f}; per-curve rmse "
                f"median {np.median(self.curve_rmse_deg) if self.curve_rmse_deg else np.nan:.2f}"
                f"; curves with rmse <= 1 and max <= 3 deg: {both}"
                + (f"; {self.unanswered} curves answered at no point (past the emulated "
                   "range from the start)" if self.unanswered else ""))
        for (yes, no), marks in (
                (("flagged near_early_ended_fe_curves", "not flagged near_early_ended_fe_curves"),
                 self.near_failed),
                (("flagged band_undercovers_random_designs",
                  "not flagged band_undercovers_random_designs"), self.undercover),
                (("FE curve ended early (short of 90 deg)", "FE curve complete (to 90 deg)"),
                 self.ended_early),
                (("FE failed (Newton), its converged part", "FE record complete"),
                 self.fe_failed)):
            for flagged in (True, False):
                sel = [i for i, f in enumerate(marks) if f == flagged]
                if not sel:
                    continue
                ok = sum(self.curve_rmse_deg[i] <= 1 and self.curve_max_deg[i] <= 3
                         for i in sel)
                cov = (float(np.mean(np.concatenate([self.inside_points[i] for i in sel])))
                       if any(self.inside_points[i].size for i in sel) else float("nan"))
                text += (f"\n{yes if flagged else no}: {len(sel)} curves, {ok} within the "
                         f"per-curve target, band coverage {cov:.3f}")
        if self.fe_deg:
            fe, ins = np.abs(np.concatenate(self.fe_deg)), np.concatenate(self.inside_points)
            bins = angle_bin(fe)
            text += "\nrmse by FE angle: " + ", ".join(
                f"{ANGLE_BINS_DEG[b]:g}-{ANGLE_BINS_DEG[b + 1]:g} deg "
                f"{np.sqrt(np.nanmean(flat[bins == b] ** 2)):.2f}"
                for b in range(len(ANGLE_BINS_DEG) - 1) if (bins == b).any())
            text += "\nband coverage by FE angle: " + ", ".join(
                f"{ANGLE_BINS_DEG[b]:g}-{ANGLE_BINS_DEG[b + 1]:g} deg {ins[bins == b].mean():.2f}"
                f" ({int((bins == b).sum())})" for b in range(len(ANGLE_BINS_DEG) - 1)
                if (bins == b).any())
        if self.force_withheld:
            text += (f"\nforce: {self.force_withheld} of {self.force_total} points "
                     "withheld in the answer (flag force_band_too_wide); the force model "
                     "at all of them:")
        if self.force_errors_mn:
            fl = np.concatenate(self.force_errors_mn)
            text += (f"\nforce: {len(self.force_errors_mn)} blocked-tip curves, rmse "
                     f"{np.sqrt(np.mean(fl**2)):.3f} mN, max {np.abs(fl).max():.3f} mN, "
                     f"band coverage {self.force_inside / max(self.force_total, 1):.3f}; "
                     f"answered at {self.force_answered} of {self.force_total} points, "
                     "band coverage there "
                     f"{self.force_answered_inside / max(self.force_answered, 1):.3f}")
        return text


def label(rec) -> str:
    d = rec.design
    return (f"{d.body_material.id}/{d.membrane_material.id} L={d.L_mm:.2f} t={d.t_mm:.2f} "
            f"T={d.T_mm:.2f} b={d.b_mm:.2f} h={d.h_mm:.3f}")


def _force(e, rec, out: HeldOut) -> None:
    c = rec.curve
    keep = c.pressure_pa > 0
    try:
        p = e.predict(rec.design, c.pressure_pa[keep])
    except InputError:
        return
    if p.force_mn is None:
        return
    answered = np.isfinite(p.force_mn)
    # the force model's own accuracy, also where the answer withholds it (band > 2x force)
    limit, force_answer_module.FORCE_BAND_LIMIT = force_answer_module.FORCE_BAND_LIMIT, np.inf
    try:
        p = e.predict(rec.design, c.pressure_pa[keep])
    finally:
        force_answer_module.FORCE_BAND_LIMIT = limit
    ok = np.isfinite(p.force_mn)
    out.force_withheld += int((ok & ~answered).sum())
    fe = c.force_mn[keep][ok]
    out.force_errors_mn.append(p.force_mn[ok] - fe)
    inside = (fe >= p.force_lower_mn[ok] - 1e-9) & (fe <= p.force_upper_mn[ok] + 1e-9)
    out.force_inside += int(inside.sum())
    out.force_answered += int(answered[ok].sum())
    out.force_answered_inside += int(inside[answered[ok]].sum())
    out.force_total += int(ok.sum())
    out.lines.append(f"{label(rec)} blocked tip: force rmse "
                     f"{np.sqrt(np.mean((p.force_mn[ok] - fe) ** 2)):.3f} mN over "
                     f"{int(ok.sum())} points (FE up to {np.abs(fe).max():.2f} mN)")


def evaluate(e, records, axis: str = "pressure") -> HeldOut:
    """The emulator ``e`` on each held-out record (``scored``: complete, or failed with its
    converged part): free tip in angle at the FE's own pressures (``axis`` "pressure":
    ``predict``) or injected volumes ("volume": ``predict_volume``); blocked tip in force."""
    out = HeldOut(axis)
    for rec in records:
        if rec.settings.tip == "blocked":
            if axis == "pressure":
                _force(e, rec, out)
            continue
        c = rec.curve
        keep = (np.abs(c.angle_deg) <= 90.0) & (c.pressure_pa > 0)
        try:
            p = (e.predict(rec.design, c.pressure_pa[keep]) if axis == "pressure"
                 else e.predict_volume(rec.design, c.volume_ul[keep]))
        except InputError as exc:
            out.refused += 1
            out.lines.append(f"{label(rec)}: refused ({exc.field}: {exc.detail[:60]}...)")
            continue
        fe = c.angle_deg[keep]
        ok = np.isfinite(p.angle_deg)
        if not ok.any():
            out.unanswered += 1
            out.lines.append(f"{label(rec)}: no point answered, all {ok.size} past the "
                             f"emulated FE range ({p.validity['fe_stop_reason']})")
            continue
        err = p.angle_deg[ok] - fe[ok]
        cover = (fe[ok] >= p.lower_deg[ok] - 1e-9) & (fe[ok] <= p.upper_deg[ok] + 1e-9)
        out.fe_deg.append(fe[ok])
        out.inside_points.append(cover)
        out.inside += int(cover.sum())
        out.total += int(ok.sum())
        out.errors_deg.append(err)
        rmse = float(np.sqrt(np.mean(err**2)))
        worst = float(np.abs(err).max())
        out.curve_rmse_deg.append(rmse)
        out.curve_max_deg.append(worst)
        out.near_failed.append("near_early_ended_fe_curves" in p.validity["flags"])
        out.undercover.append("band_undercovers_random_designs" in p.validity["flags"])
        out.ended_early.append(bool(np.abs(c.angle_deg).max() < 90.0 - 1e-6))
        out.fe_failed.append(rec.status == "failed")
        out.lines.append(f"{label(rec)}: rmse {rmse:.2f} max {worst:.2f} deg, band covers "
                         f"{cover.mean():.2f}, {int((~ok).sum())} of {ok.size} points past "
                         "the emulated FE range")
    return out


def heldout_sets(given: list[str] | None = None) -> list[str]:
    """The held-out sets a script scores: ``given``, or every random-design set kept in
    benchmarks/heldout/ (ho20*.h5 and ho4242.h5; force3040.h5, blocked tips only, apart)."""
    import glob

    return given or (sorted(glob.glob("benchmarks/heldout/ho20*.h5"))
                     + ["benchmarks/heldout/ho4242.h5"])


def scored(rec) -> bool:
    """Whether a held-out record is scored: a complete FE curve, or the converged part of
    one whose Newton iteration failed (a design drawn at random is judged "over each
    converged curve", the failed ones too: 37 of 504 held-out free-tip curves)."""
    c = rec.curve
    return rec.status == "complete" or (rec.status == "failed" and c is not None
                                        and int((c.pressure_pa > 0).sum()) >= 2)


def scored_free_records(given: list[str] | None = None):
    """Every scored free-tip record (``scored``) of the held-out sets (``heldout_sets``),
    in order: what the scripts that read the emulator's misses go through."""
    from solver.store import CurveStore

    for path in heldout_sets(given):
        with CurveStore(path) as store:
            for rec in store.records():
                if scored(rec) and rec.settings.tip != "blocked":
                    yield rec


def forget(model) -> None:
    """Clear the emulator's design memo (``surrogate/emulator/design_memo.py``), so that
    the next query is a design's first; other models keep none."""
    memo = getattr(model, "_memo", None)
    if memo is not None:
        memo.clear()


def interleaved(models: dict, call, rounds: int, per_round: int) -> dict[str, str]:
    """Median time of ``call(model)`` per model, the models taking turns (``rounds`` of
    ``per_round`` calls each: the machine's load hits all alike), and its ratio to the
    first model's."""
    times: dict[str, list[float]] = {k: [] for k in models}
    for _ in range(rounds):
        for k, m in models.items():
            for _ in range(per_round):
                t0 = time.perf_counter()
                call(m)
                times[k].append(time.perf_counter() - t0)
    first = float(np.median(next(iter(times.values()))))
    return {k: f"median {1e3 * np.median(t):.3f} ms, ratio to the first "
               f"{np.median(t) / first:.2f}" for k, t in times.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--heldout", required=True)
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--exponential", default="service/data/surrogate.json")
    ap.add_argument("--axis", choices=("pressure", "volume", "both"), default="both",
                    help="compare at the FE's own pressures, its own injected volumes, or both")
    ap.add_argument("--compare", help="a second emulator file, timed interleaved with the "
                    "first in the same run (a ratio)")
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    with CurveStore(args.heldout) as db:
        records = [r for r in db.records() if scored(r)]
    for axis in (("pressure", "volume") if args.axis == "both" else (args.axis,)):
        result = evaluate(e, records, axis)
        print(f"-- by {axis}\n" + "\n".join(result.lines) + "\n\n" + result.summary())
    from solver import Design

    d = Design().validated()
    pressures = np.linspace(0, 2000, 100)
    exp = load_surrogate(args.exponential)

    def timed(model, again: bool) -> float:
        """Median time of one query; ``again``: the design asked before (the emulator's
        design memo holds its curve), else its first query (the memo cleared)."""
        ts = []
        for _ in range(2000):
            if not again:
                forget(model)
            t0 = time.perf_counter()
            model.predict(d, pressures)
            ts.append(time.perf_counter() - t0)
        return float(np.median(ts))

    te, te_again, tx = timed(e, False), timed(e, True), timed(exp, True)
    print(f"query, 100 pressures with bands: emulator {1e3 * te:.3f} ms for a design's first "
          f"query, {1e3 * te_again:.3f} ms for the same design again (design_memo.py), "
          f"exponential {1e3 * tx:.3f} ms (ratios {te / tx:.2f}, {te_again / tx:.2f})")
    if args.compare:
        models = {args.emulator: e, args.compare: load_emulator(args.compare), "exponential": exp}
        # each call a design's first query: the two files' models compared, not their memos
        for k, t in interleaved(models, lambda m: forget(m) or m.predict(d, pressures), 40,
                                100).items():
            print(f"interleaved, {k}: {t}")
        # a query by injected volume asks the variance of every volume node (one product
        # per node's kernel): the two emulator files, interleaved the same way
        volumes = np.linspace(0.5, 60.0, 100)
        files = {k: models[k] for k in (args.emulator, args.compare)}
        for k, t in interleaved(files, lambda m: forget(m) or m.predict_volume(d, volumes),
                                20, 50).items():
            print(f"interleaved, 100 volumes with bands, {k}: {t}")
        # a design emulated to end early also reads the means conditioned on the
        # early-ended database curves (early_ended_nodes): the held-out design whose FE
        # curve the first file's range model ends earliest
        rec = min(records, key=lambda r: _emulated_end_deg(e, r.design))
        print(f"the earliest-ending held-out design (emulated end "
              f"{_emulated_end_deg(e, rec.design):.0f} deg): {label(rec)}")
        for k, t in interleaved(files, lambda m: forget(m) or m.predict(rec.design, pressures),
                                40, 100).items():
            print(f"interleaved, 100 pressures with bands there, {k}: {t}")


def _emulated_end_deg(e, design) -> float:
    """Where the emulator's range model ends the design's FE curve (deg; inf where it
    does not answer or has no range model)."""
    try:
        point = locate(design, reduced=True)
        pe = e._pair(point)
    except InputError:
        return float("inf")
    return float("inf") if pe.range_model is None else pe.emulated_end_deg(point.coordinates())[0]


if __name__ == "__main__":
    main()
