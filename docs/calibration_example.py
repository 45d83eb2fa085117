"""Make the worked example's data (docs/calibration.md): SYNTHETIC measurements.

Truth: the paper's constants (a = 0.101 deg/mm, a_t = 731.2 Pa, b_t = 7.179 /mm, log10),
an inlet resistance of 70 Pa per ul/s and a 1.5 deg pre-curvature; four designs of the
paper's Table 2 at 1.0 and 2.5 ul/s, three specimens each (2 % scatter of A), angle read
every 1 s for 10 s with 0.4 deg noise. Run from the repository root:

    .venv/bin/python docs/calibration_example.py surrogate/calibration/data/example_lab.csv
"""

from __future__ import annotations

import csv
import math
import sys

import numpy as np

DESIGNS = ((4.1, 0.5), (7.1, 0.5), (11.1, 0.5), (7.1, 1.0))
R_TRUE, OFFSET_TRUE = 70.0, 1.5


def rows(seed: int = 7) -> list[dict]:
    rng = np.random.default_rng(seed)
    times = np.arange(0.0, 11.0)
    out, k = [], 0
    for L, t in DESIGNS:
        tau = 731.2 * math.log10(7.179 * t)
        A = 0.101 * L
        for q in (1.0, 2.5):
            for _ in range(3):
                k += 1
                spec = 1 + 0.02 * rng.standard_normal()
                t_c = 8.0 * (1 + 0.1 * rng.standard_normal())
                p_end = tau * math.log(1 + 80.0 / A) * (1 + 0.03 * rng.standard_normal())
                pc = p_end * (1 - np.exp(-times / t_c)) / (1 - math.exp(-10 / t_c))
                angle = spec * A * np.expm1(pc / tau) + OFFSET_TRUE
                angle += 0.4 * rng.standard_normal(times.size)
                for ts, p, a in zip(times, pc + R_TRUE * q, angle, strict=True):
                    out.append({"curve_id": f"spec{k:02d}", "L_mm": L, "t_mm": t,
                                "body_material": "pdms_1_10",
                                "membrane_material": "ecoflex_00_30",
                                "pressure_pa": round(float(p), 1),
                                "angle_deg": round(float(a), 2), "time_s": ts,
                                "flow_ul_s": q})
    return out


if __name__ == "__main__":
    data = rows()
    with open(sys.argv[1], "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(data[0]))
        w.writeheader()
        w.writerows(data)
