"""Two small lab data sets with a gauge read to 1.5 % (tests/data/lab_gauge_noise_*.csv),
made from FE solves (``solver.solve``, default settings), never from the calibration's
forms; the tests read them (test_calibration_history.py).

Designs: L 9.0 / t 0.6 mm and L 13.0 / t 0.7 mm, PDMS 1:10 body on Ecoflex 00-30, the
standard T, b, h. A syringe pump at Q ul/s; 3 specimens a design with 2 % scatter of
pressure and angle; reading noise 0.7 deg and 1.5 % + 3 Pa of the gauge (a lab's
gauge); angle to 0.1 deg, pressure to 1 Pa. Each row carries ``pump``: what the pump
did before the reading (the truth the tests compare the history read off the data
with; drop it to read the data as a lab without the pump's log would give them).

* ``loading_two_flows``: the nominal designs, loading 10 s at 1 and 3 ul/s read every
  1 s, an inlet resistance of 80 Pa per ul/s (the gauge reads p + R Q);
* ``loop_stiff_membrane``: the membrane 25 % stiffer than its preset (the FE solve of
  that design), 2 ul/s, loading 12.5 s, holding 5 s, withdrawing 12.5 s, read every
  2.5 s; written as a German Excel writes CSV (';', decimal commas, a byte-order mark);
* ``loop_thick_membrane``: the membranes 0.08 mm thicker than written (the FE solves of
  t 0.68 and 0.78 mm, written 0.6 and 0.7), the same loop, German Excel too.
* ``loop_kink``: the nominal designs, the same loop at 1 and 2 ul/s, and a kink forming
  in the tubing after 7.5 s: from then on the gauge reads p + R Q d with R 300 Pa per
  ul/s (d the pump's state), an effect outside the catalogue (its R changes mid-run).

Regenerate (6 solves of ~20-45 s; run alone):

    .venv/bin/python tests/lab_gauge_noise.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data"
DESIGNS = {"A": (9.0, 0.6), "B": (13.0, 0.7)}
COLUMNS = ("curve_id", "L_mm", "t_mm", "body_material", "membrane_material",
           "pressure_pa", "angle_deg", "time_s", "flow_ul_s", "pump")


def fe_curve(L_mm: float, t_mm: float, membrane_mu_scale: float = 1.0):
    from solver import Design, SolverSettings, solve
    from solver.design_space import scaled_material

    c = solve(Design(L_mm=L_mm, t_mm=t_mm, body_material=scaled_material("pdms_1_10", 1.0),
                     membrane_material=scaled_material("ecoflex_00_30", membrane_mu_scale)),
              SolverSettings())
    return np.asarray(c.volume_ul), np.asarray(c.pressure_pa), np.asarray(c.angle_deg)


def _pump(protocol, q: float):
    t = np.arange(0.0, sum(d for _, d in protocol) + 1e-9, 1e-3)
    v, d = np.zeros_like(t), np.zeros_like(t)
    t0 = v0 = 0.0
    for kind, dur in protocol:
        m = (t > t0 + 1e-12) & (t <= t0 + dur + 1e-12)   # a reading at a switch: before
        rate = {"load": q, "hold": 0.0, "unload": -q}[kind]
        v[m] = v0 + rate * (t[m] - t0)
        d[m] = np.sign(rate)
        t0, v0 = t0 + dur, v0 + rate * dur
    return t, v, d


def measure(curves: dict, flows, protocol, read_s: float, R_pa_per_ul_s: float = 0.0,
            seed: int = 1, kink_after_s: float | None = None) -> list[dict]:
    rng = np.random.default_rng(seed)
    rows = []
    for key, (L, t_mm) in DESIGNS.items():
        vv, pv, av = curves[key]   # the actuator as built; the row has the nominal
        for q in flows:
            for s in range(3):
                sp, sa = 1 + 0.02 * rng.standard_normal(2)
                tt, v, d = _pump(protocol, q)
                assert v.max() < vv[-1]
                R = np.full_like(tt, R_pa_per_ul_s)
                if kink_after_s is not None:
                    R[tt > kink_after_s] = 300.0
                gauge = sp * np.interp(v, vv, pv) + R * q * d
                angle = sa * np.interp(v, vv, av)
                reads = np.arange(read_s, tt[-1] + 1e-9, read_s)
                for k, i in enumerate(np.searchsorted(tt, reads - 1e-9)):
                    p = gauge[i] * (1 + 0.015 * rng.standard_normal()) \
                        + 3 * rng.standard_normal()
                    a = angle[i] + 0.7 * rng.standard_normal()
                    rows.append({"curve_id": f"{key}-q{q:g}-s{s + 1}", "L_mm": L, "t_mm": t_mm,
                                 "body_material": "pdms_1_10",
                                 "membrane_material": "ecoflex_00_30",
                                 "pressure_pa": round(float(p)),
                                 "angle_deg": round(float(a), 1),
                                 "time_s": round(float(reads[k]), 2), "flow_ul_s": q,
                                 "pump": ("unload", "hold", "load")[int(d[i]) + 1]})
    return rows


def write(rows: list[dict], path: Path, comment: str, german: bool = False) -> None:
    sep = ";" if german else ","

    def cell(x: object) -> str:
        return str(x).replace(".", ",") if german and isinstance(x, float) else str(x)

    lines = [f"# {comment}", sep.join(COLUMNS)]
    lines += [sep.join(cell(r[c]) for c in COLUMNS) for r in rows]
    path.write_bytes(("\ufeff" if german else "").encode() + ("\r\n".join(lines) + "\r\n").encode())


def main() -> int:
    nominal = {k: fe_curve(L, t, 1.0) for k, (L, t) in DESIGNS.items()}
    stiff = {k: fe_curve(L, t, 1.25) for k, (L, t) in DESIGNS.items()}
    thick = {k: fe_curve(L, round(t + 0.08, 6)) for k, (L, t) in DESIGNS.items()}
    source = "made by tests/lab_gauge_noise.py from FE solves (solver.solve, default settings)"
    write(measure(nominal, (1.0, 3.0), (("load", 10.0),), 1.0, R_pa_per_ul_s=80.0),
          DATA / "lab_gauge_noise_loading_two_flows.csv",
          source + ": inlet resistance 80 Pa per ul/s, gauge noise 1.5 %")
    write(measure(stiff, (2.0,), (("load", 12.5), ("hold", 5.0), ("unload", 12.5)), 2.5),
          DATA / "lab_gauge_noise_loop_stiff_membrane.csv",
          source + ": membrane x1.25, gauge noise 1.5 %", german=True)
    write(measure(thick, (2.0,), (("load", 12.5), ("hold", 5.0), ("unload", 12.5)), 2.5),
          DATA / "lab_gauge_noise_loop_thick_membrane.csv",
          source + ": membranes 0.08 mm thicker than written, gauge noise 1.5 %", german=True)
    write(measure(nominal, (1.0, 2.0), (("load", 12.5), ("hold", 5.0), ("unload", 12.5)), 2.5,
                  seed=3, kink_after_s=7.5),
          DATA / "lab_gauge_noise_loop_kink.csv",
          source + ": a kink of 300 Pa per ul/s from 7.5 s, gauge noise 1.5 %")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    raise SystemExit(main())
