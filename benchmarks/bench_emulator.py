"""The emulator against held-out FE curves, and its query time.

    python benchmarks/heldout_designs.py --n 16 --seed 2026 --db heldout.h5
    python benchmarks/bench_emulator.py --heldout heldout.h5 [--emulator service/data/emulator.json]

For every held-out curve (random designs inside the box, not in the database, solved by
the default FE): the emulator at the FE's own pressures up to 90 deg, and at its own
injected volumes (the syringe-pump view, ``--axis``) -- RMSE, max error and the share of
FE points inside the 95 % band; a refusal (near the Ecoflex/Ecoflex
balance, or too few curves) is counted as such. Query time: 100 pressures with bands,
median of 2000 calls, next to the exponential model's in the same run (a ratio).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from solver.errors import InputError
from solver.store import CurveStore
from surrogate import load_surrogate
from surrogate.emulator import load_emulator


def compare(e, records, axis: str) -> None:
    """Print per-curve and overall RMSE / band coverage of the emulator at the FE's own
    pressures (``axis`` "pressure": ``predict``) or its own injected volumes ("volume":
    ``predict_volume``, the syringe-pump view)."""
    rows, all_err, inside, total = [], [], 0, 0
    for rec in records:
        c = rec.curve
        keep = (np.abs(c.angle_deg) <= 90.0) & (c.pressure_pa > 0)
        label = (f"{rec.design.body_material.id}/{rec.design.membrane_material.id} "
                 f"L={rec.design.L_mm:.2f} t={rec.design.t_mm:.2f} T={rec.design.T_mm:.2f} "
                 f"b={rec.design.b_mm:.2f} h={rec.design.h_mm:.3f}")
        try:
            p = (e.predict(rec.design, c.pressure_pa[keep]) if axis == "pressure"
                 else e.predict_volume(rec.design, c.volume_ul[keep]))
        except InputError as exc:
            rows.append(f"{label}: refused ({exc.field}: {exc.detail[:60]}...)")
            continue
        fe = c.angle_deg[keep]
        ok = np.isfinite(p.angle_deg)
        err = p.angle_deg[ok] - fe[ok]
        cover = (fe[ok] >= p.lower_deg[ok] - 1e-9) & (fe[ok] <= p.upper_deg[ok] + 1e-9)
        inside += int(cover.sum())
        total += int(ok.sum())
        all_err.append(err)
        rows.append(f"{label}: rmse {np.sqrt(np.mean(err**2)):.2f} max {np.abs(err).max():.2f}"
                    f" deg, band covers {cover.mean():.2f}, {int((~ok).sum())} of "
                    f"{ok.size} points past the emulated FE range")
    flat = np.concatenate(all_err) if all_err else np.array([np.nan])
    print(f"-- by {axis}")
    print("\n".join(rows))
    print(f"\nall {len(all_err)} answered curves ({total} points), by {axis}: rmse "
          f"{np.sqrt(np.mean(flat**2)):.2f} deg, max {np.abs(flat).max():.2f} deg, "
          f"95 % band coverage {inside / max(total, 1):.3f}; "
          f"per-curve rmse median {np.median([np.sqrt(np.mean(x**2)) for x in all_err]):.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--heldout", required=True)
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--exponential", default="service/data/surrogate.json")
    ap.add_argument("--axis", choices=("pressure", "volume", "both"), default="both",
                    help="compare at the FE's own pressures, its own injected volumes, or both")
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    with CurveStore(args.heldout) as db:
        records = [r for r in db.records() if r.status == "complete"]
    for axis in (("pressure", "volume") if args.axis == "both" else (args.axis,)):
        compare(e, records, axis)
    from solver import Design

    d = Design().validated()
    pressures = np.linspace(0, 2000, 100)
    exp = load_surrogate(args.exponential)

    def timed(model) -> float:
        ts = []
        for _ in range(2000):
            t0 = time.perf_counter()
            model.predict(d, pressures)
            ts.append(time.perf_counter() - t0)
        return float(np.median(ts))

    te, tx = timed(e), timed(exp)
    print(f"query, 100 pressures with bands: emulator {1e3 * te:.3f} ms, exponential "
          f"{1e3 * tx:.3f} ms (ratio {te / tx:.2f})")


if __name__ == "__main__":
    main()
