"""Recalibrate the shipped emulator's force bands after a change to how a force answer is
read, without refitting its GPs.

    python benchmarks/recalibrate_force_bands.py [--emulator service/data/emulator.json]
        [--band-calibration-db service/data/band-calibration.h5]

The force bands' last step in ``balloon fit`` is ``calibrate_force_on_random_designs``: each
group's band factor iterated to its fixed point on the blocked-tip FE curves of random
designs (its rounds start from the factor at hand and stop when it moves less than its
tolerance, so the fixed point does not depend on where it starts). When the force answer
changes and the GPs do not (the forty-ninth session: the force variable read by PCHIP
between its pressure nodes instead of linearly), the fit's own command would give the same
GPs and these factors; this runs that last step alone on the shipped file (a few minutes,
where a refit takes 20-40) and records it in the file's provenance
(``force_bands_recalibrated``: the code's commit, when, this command).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

from solver.store import CurveStore
from surrogate.emulator import load_emulator
from surrogate.emulator.file import save_emulator
from surrogate.emulator.force_calibration import calibrate_force_on_random_designs
from surrogate.fit_provenance import refit_step


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--band-calibration-db", default="service/data/band-calibration.h5")
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    before = {k: pe.force_band_factor for k, pe in e.pairs.items()}
    with CurveStore(args.band_calibration_db) as db:
        records = list(db.records())
    source = dict(e.report.get("random_design_force_calibration", {}).get("source", {}))
    calibrated = calibrate_force_on_random_designs(e, records, source=source)
    provenance = dict(calibrated.provenance)
    provenance["force_bands_recalibrated"] = refit_step(
        "python benchmarks/recalibrate_force_bands.py " + " ".join(sys.argv[1:]))
    calibrated = replace(calibrated, provenance=provenance)
    save_emulator(calibrated, args.emulator)
    cal = calibrated.report["random_design_force_calibration"]
    for key, pe in calibrated.pairs.items():
        print(f"{key}: force band factor {before[key]:.4f} -> {pe.force_band_factor:.4f}")
    print("coverage after:", cal["coverage_after"]["all"])


if __name__ == "__main__":
    main()
