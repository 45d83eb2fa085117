"""Give the shipped emulator's balance models the band multipliers of curves that turn
back, without refitting their GPs.

    python benchmarks/recalibrate_balance_bands.py [--emulator service/data/emulator.json]
        [--db service/data/curves.h5]

``balance.fit_balance_model`` fits the balance model's band multipliers on its own curves'
leave-one-out predictions (``balance.loo_band_scales``); since the fiftieth session it also
fits them twice: on the curves whose leave-one-out mean turns back (``turns_back``) and on
the rest, where it had one pair over every curve. The leave-one-out predictions are a
function of the fitted GP alone, so this runs that last step on the shipped file (about a
minute, where a refit takes 20-40), checks that the file's pair is this GP's (over every
curve, as the former fit made it), and records the step in the file's provenance
(``balance_bands_recalibrated``: the code's commit, when, this command).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

import numpy as np

from solver.store import CurveStore
from surrogate.emulator import load_emulator
from surrogate.emulator.balance import loo_band_scales, on_nodes
from surrogate.emulator.database_rows import collect_rows
from surrogate.emulator.file import save_emulator
from surrogate.fit_provenance import refit_step


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--db", default="service/data/curves.h5")
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    with CurveStore(args.db) as db:
        free, _, _ = collect_rows(db.records())
    models = dict(e.balance_models)
    report = dict(e.report)
    balance_report = dict(report.get("balance", {}))
    for group, model in e.balance_models.items():
        used = [c for _, c in free[group].by_volume if on_nodes(*c) is not None]
        if len(used) != model.designs:
            sys.exit(f"{group}: the database gives {len(used)} balance curves where the "
                     f"model was fitted on {model.designs}: not the database it was fitted on")
        scales, turn, calibration = loo_band_scales(model.gp, used)
        # the same GP and curves: the file's pair is the one over every curve (made
        # before format 18) or the non-turning curves' (made since)
        had = (model.band_scale_volume, model.band_scale_pressure)
        if not any(np.allclose(had, c, rtol=1e-6)
                   for c in (scales, calibration["every_curve_band_scales"])):
            sys.exit(f"{group}: the file's multipliers {had} are not this GP's "
                     f"({calibration['every_curve_band_scales']} over every curve)")
        models[group] = replace(model, band_scale_volume=scales[0],
                                band_scale_pressure=scales[1], turn_scales=turn)
        balance_report[group] = {**dict(balance_report.get(group, {})), **calibration}
        print(f"{group}: {calibration['turning_curves']} of {len(used)} curves turn back; "
              f"multipliers {had[0]:.3f} / {had[1]:.3f} (volume / pressure) -> "
              f"{scales[0]:.3f} / {scales[1]:.3f}, turning "
              f"{'none' if turn is None else f'{turn[0]:.3f} / {turn[1]:.3f}'}")
    report["balance"] = balance_report
    provenance = dict(e.provenance)
    provenance["balance_bands_recalibrated"] = refit_step(
        "python benchmarks/recalibrate_balance_bands.py " + " ".join(sys.argv[1:]))
    save_emulator(replace(e, balance_models=models, report=report, provenance=provenance),
                  args.emulator)


if __name__ == "__main__":
    main()
