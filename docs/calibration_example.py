"""The worked example of docs/calibration.md: lab-like data made from FE curves, then the
calibration, its report and its plot.

Data: the cached FE solves of the project's own solver (tests/data/
fe_calibration_curves.npz) read the way a lab reads an actuator (tests/calibration_lab.py):
three of the paper's designs (L 7.1 / t 0.75, L 11.1 / t 0.5, L 4.1 / t 0.5 mm), 3
specimens each with 2 % specimen scatter, pumped at 1.25 and 2.5 ul/s for 6 s, held 4 s
and withdrawn 6 s, angle and pressure read every 1 s (0.7 deg, 3 Pa noise). Truth: an
inlet resistance of 60 Pa per ul/s and a 1.5 deg pre-curvature. Run from the repository
root:

    .venv/bin/python docs/calibration_example.py

writes surrogate/calibration/data/example_lab.csv, docs/calibration-example-report.json
and docs/calibration-example.png. The baseline is the shipped design-space emulator
(service/data/emulator.json; ``balloon calibrate`` uses it by default);
``balloon calibrate surrogate/calibration/data/example_lab.csv --model paper`` runs the
same data against the paper's exponential model.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))

import calibration_lab as lab  # noqa: E402

from surrogate.calibration import jsonable, plot_calibration, run_calibration  # noqa: E402

TRUTH = lab.Truth(R_pa_per_ul_s=60.0, offset_deg=1.5)
LAB = lab.Lab(flows_ul_s=(1.25, 2.5), protocol=lab.LOOP, seed=7)


def main() -> int:
    rows = lab.measure(LAB, TRUTH)
    data = ROOT / "surrogate" / "calibration" / "data" / "example_lab.csv"
    with open(data, "w", newline="") as fh:
        fh.write("# made by docs/calibration_example.py from FE curves: inlet resistance "
                 "60 Pa per ul/s, angle offset 1.5 deg\n")
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    cal = run_calibration(rows, lab.emulator())
    report = jsonable(cal.report)
    (ROOT / "docs" / "calibration-example-report.json").write_text(
        json.dumps(report, indent=1) + "\n")
    plot_calibration(cal, ROOT / "docs" / "calibration-example.png")
    print(f"true floor {lab.true_floor(LAB, TRUTH):.2f} deg")
    for k in ("rmse_model_deg", "rmse_before_deg", "rmse_after_deg", "noise_floor_deg",
              "selected_effects", "unexplained_rms_deg", "residual_structured_after"):
        print(k, report[k])
    print(json.dumps(report["fitted"]["effects"], indent=1))
    print(report["interpretation"])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
