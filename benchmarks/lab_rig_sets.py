"""Lab data sets made as a lab makes them, from FE solves (``solver.solve``, default
settings), never from the calibration's forms: the forty-first session's audit of
`balloon calibrate` (benchmarks/RESULTS.md) and nine files of tests/data; the
forty-second session's sets N1-N5 on three more designs (D8-D10), to check its changes on
designs they were not made on; the forty-third session's fresh sets N6-N13 on three more
(D11-D13: a stiffness-scaled body, the reversed pair, PDMS 1:15), their truths and seeds
written here before any was calibrated; the forty-fifth session's fresh sets N14-N21 on
three more (D14-D16: Ecoflex/Ecoflex, a membrane-scaled Ecoflex x 0.8, a short PDMS 1:10
body), likewise; the forty-sixth session's fresh sets N22-N29 on three more (D17-D19:
the reversed pair bending towards its membrane, a long body `pdms_1_10*1.6`, a thick
membrane), likewise; the forty-seventh session's fresh sets N30-N37 on three more
(D20-D22: Ecoflex on an Ecoflex membrane twice as stiff, bending towards it; a short
thick PDMS 1:15 body; a deep chamber under a soft PDMS 1:10 body), likewise; the
forty-eighth session's fresh sets N38-N45 on three more (D23-D25: a long wide shallow
chamber, a stiffened Ecoflex body on Ecoflex, the reversed pair on a softened PDMS 1:15
membrane), likewise; the forty-ninth session's fresh sets N46-N53 on three more (D26-D28,
drawn at random in the box), likewise; the fiftieth session's fresh sets N54-N61 on three
more (D29-D31, drawn likewise), likewise.

Designs inside the emulator's box and not in service/data/curves.h5 (the four
material pairs, L 5.4-16.3 mm, odd T, b, h); each design's three specimens are three FE
solves of the membrane thickness x 0.96, 1 and 1.045 (scatter), and each specimen has its
own stiffness (both layers' mu x s, s ~ N(1, 0.07) within +-10 %: the pressure axis x s,
the shape at a volume unchanged). A syringe pump (load, hold, unload, switching at
readings), the camera read every dt to 0.1 deg with 0.7 deg noise, the gauge at the pump
with a zero within +-3 Pa and 1.5 % + 2 Pa noise, written to 1 Pa in kPa, headers with
units, a run column, German Excel's ';' and decimal commas. Effects applied physically:
a membrane 10 % stiffer (its FE solves), the mount tilted (angle + offset), air in the
line (V_pump = V_chamber + C p), a laminar leak (dV_lost/dt = G p, integrated on a
2 ms grid), a standard linear solid relaxing the pressure at a held volume, a camera
whose view is tilted phi to the bending plane (tan a' = cos phi tan a: outside the
catalogue), a gauge reading 60 Pa high; for N6-N13 also a batch whose both layers are
8 % stiffer (the pressure axis x 1.08), a body 12 % stiffer (its FE solves), a narrow
long inlet (the gauge at the pump reads R x the flow just before each stamp above the
chamber), air in the line with the gauge's zero off, and a camera whose time stamps are
0.5 s late (outside the catalogue); lab habits: two specimens, fewer readings, an unload
without a hold, a fast and a slow pump, pressures in mbar or psi and times in ms (the
unit in the header); for N14-N21 also a membrane 10 % softer (its FE solves), Mullins
softening on the unloading (outside the catalogue), and readings every 0.5 s, hPa, inH2O,
one specimen run four times, a loading without an unloading and a hold of 30 s; for
N22-N29 also a membrane 0.08 mm thicker (its FE solves), a gauge drifting at +4 Pa/s,
an inlet with air in the line at two flow rates, the moduli drifting over the session (a
lamp warming the rig: outside the catalogue), creep of the bend, a camera gain with the
gauge's zero off, and a staircase of holds, angles in radians, the pump's volume in ml
(with and without time), mmHg, time as mm:ss text, a units row under the header, a wide
layout with a column per specimen, and 4 readings a curve on 2 specimens; for N30-N37
also a gauge whose calibration errs quadratically and a rim that leaks only above a
pressure (both outside the catalogue), the gauge re-zeroed on each day of measuring,
and a logger's lines of text above the header, a date column, a tab-separated export with
decimal commas, the flow in ul/min with the time in min, and two flow rates in radians;
for N38-N45 also Mullins softening after the first loading only (two runs a specimen)
and an angle sensor that saturates at its stop (both outside the catalogue), and a
logger's timestamp column (ISO 8601 as the only time axis, day/month/year with the time
of day, epoch seconds), a header 'Pressure kPa' (the unit after a space), the specimens
told apart by a 'Sample' column, and two empty columns at the end of every line; for
N46-N53 also a gauge that lags the pressure (outside the catalogue) and an angle sensor
that reads exactly its stop, a small tilt of the mount and a small zero of the gauge, and
a blank line after each specimen, the columns in another order, and a logger's extra
columns (the rig's temperature, a note); for N54-N61 also a dial gauge's dead band
(outside the catalogue) and a leak shown by an unloading without a hold, and units in
square brackets with a degree and a micro sign, a byte-order mark with quoted decimal
commas in a comma-separated export, Windows-1252 text and a logger's line after the last
reading.

    .venv/bin/python benchmarks/lab_rig_sets.py --cache FE_DIR --out SETS_DIR [SET ...]
    .venv/bin/python benchmarks/lab_rig_sets.py --cache FE_DIR --test-data [SET ...]

The first solves what the named sets need and the cache lacks (all: 28 x 3 + 8 x 3
solves of 5-90 s; run alone) and
writes each set as CSV (and the API's JSON rows); ``--test-data`` writes the 34 sets
(eleven with the pump's log) that tests/test_calibration_history.py and
tests/test_calibration_gauge_zero.py read (tests/data/lab_gauge_noise_*.csv; N2's too, for
test_calibration_exact_alike.py; N8's, N9's, N11's and N13's for
test_calibration_lab_fresh.py; N15's and N21's for test_calibration_lab_s45.py; N22's and
N24's, N23's, N26's and N27's, as their habits write them, N25's, N28's and N29's for
test_calibration_lab_s46.py; N30's and N34's for test_calibration_lab_s47.py; N38's,
N39's, N40's, N42's, N43's and N44's for test_calibration_lab_s48.py; N45's, N46's, N47's
and N52's for test_calibration_lab_s49.py; N53's, N55's and N60's for
test_calibration_lab_s50.py), or of them the sets named.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

import numpy as np
from scipy.interpolate import PchipInterpolator

DESIGNS = {
    "D1": dict(L_mm=9.3, t_mm=0.63, T_mm=1.27, b_mm=1.55, h_mm=0.17,
               body_material="pdms_1_10", membrane_material="ecoflex_00_30"),
    "D2": dict(L_mm=12.4, t_mm=0.82, T_mm=0.85, b_mm=2.1, h_mm=0.22,
               body_material="pdms_1_15", membrane_material="ecoflex_00_30"),
    "D3": dict(L_mm=6.2, t_mm=0.71, T_mm=1.62, b_mm=1.35, h_mm=0.13,
               body_material="ecoflex_00_30", membrane_material="ecoflex_00_30"),
    "D4": dict(L_mm=14.6, t_mm=0.58, T_mm=0.74, b_mm=1.9, h_mm=0.26,
               body_material="ecoflex_00_30", membrane_material="pdms_1_15"),
    "D5": dict(L_mm=16.3, t_mm=1.06, T_mm=1.85, b_mm=2.25, h_mm=0.28,
               body_material="pdms_1_10", membrane_material="ecoflex_00_30"),
    "D6": dict(L_mm=5.4, t_mm=0.61, T_mm=1.12, b_mm=1.15, h_mm=0.11,
               body_material="pdms_1_15", membrane_material="ecoflex_00_30"),
    "D7": dict(L_mm=10.8, t_mm=0.95, T_mm=0.68, b_mm=2.0, h_mm=0.19,
               body_material="ecoflex_00_30", membrane_material="ecoflex_00_30"),
    # the forty-second session's designs, solved for the sets N1-N5 only
    "D8": dict(L_mm=7.1, t_mm=0.9, T_mm=0.95, b_mm=1.75, h_mm=0.24,
               body_material="pdms_1_10", membrane_material="ecoflex_00_30"),
    "D9": dict(L_mm=11.3, t_mm=0.74, T_mm=1.45, b_mm=1.6, h_mm=0.15,
               body_material="ecoflex_00_30", membrane_material="pdms_1_15"),
    "D10": dict(L_mm=15.2, t_mm=0.55, T_mm=1.05, b_mm=1.25, h_mm=0.12,
                body_material="pdms_1_15", membrane_material="ecoflex_00_30"),
    # the forty-third session's designs, solved for the fresh sets N6-N13 only
    "D11": dict(L_mm=8.4, t_mm=0.78, T_mm=1.33, b_mm=1.45, h_mm=0.21,
                body_material="pdms_1_10*1.3", membrane_material="ecoflex_00_30"),
    "D12": dict(L_mm=13.7, t_mm=0.67, T_mm=1.18, b_mm=2.05, h_mm=0.16,
                body_material="ecoflex_00_30", membrane_material="pdms_1_15"),
    "D13": dict(L_mm=10.2, t_mm=1.1, T_mm=1.7, b_mm=1.8, h_mm=0.27,
                body_material="pdms_1_15", membrane_material="ecoflex_00_30"),
    # the forty-fifth session's designs, solved for the fresh sets N14-N21 only
    "D14": dict(L_mm=6.8, t_mm=0.55, T_mm=1.9, b_mm=1.1, h_mm=0.24,
                body_material="ecoflex_00_30", membrane_material="ecoflex_00_30"),
    "D15": dict(L_mm=9.6, t_mm=0.62, T_mm=1.52, b_mm=1.7, h_mm=0.19,
                body_material="pdms_1_15", membrane_material="ecoflex_00_30*0.8"),
    "D16": dict(L_mm=5.1, t_mm=0.55, T_mm=0.8, b_mm=1.25, h_mm=0.28,
                body_material="pdms_1_10", membrane_material="ecoflex_00_30"),
    # the forty-sixth session's designs, solved for the fresh sets N22-N29 only: the
    # reversed pair bending towards its membrane, a long stiffened body, a thick membrane
    "D17": dict(L_mm=8.8, t_mm=0.92, T_mm=1.42, b_mm=2.3, h_mm=0.14,
                body_material="ecoflex_00_30", membrane_material="pdms_1_15"),
    "D18": dict(L_mm=15.4, t_mm=0.7, T_mm=1.05, b_mm=1.5, h_mm=0.22,
                body_material="pdms_1_10*1.6", membrane_material="ecoflex_00_30"),
    "D19": dict(L_mm=11.6, t_mm=1.12, T_mm=1.6, b_mm=2.15, h_mm=0.13,
                body_material="pdms_1_10", membrane_material="ecoflex_00_30"),
    # the forty-seventh session's designs, solved for the fresh sets N30-N37 only: Ecoflex
    # on an Ecoflex membrane twice as stiff, a short thick PDMS 1:15 body, a deep chamber
    "D20": dict(L_mm=10.6, t_mm=0.66, T_mm=0.64, b_mm=1.95, h_mm=0.18,
                body_material="ecoflex_00_30", membrane_material="ecoflex_00_30*2"),
    "D21": dict(L_mm=5.2, t_mm=0.84, T_mm=1.88, b_mm=1.05, h_mm=0.16,
                body_material="pdms_1_15", membrane_material="ecoflex_00_30"),
    "D22": dict(L_mm=12.9, t_mm=0.57, T_mm=0.92, b_mm=1.4, h_mm=0.28,
                body_material="pdms_1_10*0.7", membrane_material="ecoflex_00_30"),
    # the forty-eighth session's designs, solved for the fresh sets N38-N45 only: a long
    # wide shallow chamber under PDMS 1:10, a stiffened Ecoflex body on Ecoflex, the
    # reversed pair on a softened PDMS 1:15 membrane, long (away from the short, thick
    # corner where the emulator misses: D21)
    "D23": dict(L_mm=13.4, t_mm=0.88, T_mm=1.22, b_mm=2.35, h_mm=0.12,
                body_material="pdms_1_10", membrane_material="ecoflex_00_30"),
    "D24": dict(L_mm=7.6, t_mm=0.52, T_mm=1.12, b_mm=2.2, h_mm=0.2,
                body_material="ecoflex_00_30*1.5", membrane_material="ecoflex_00_30"),
    "D25": dict(L_mm=16.8, t_mm=0.76, T_mm=1.48, b_mm=1.2, h_mm=0.21,
                body_material="ecoflex_00_30", membrane_material="pdms_1_15*0.6"),
    # the forty-ninth session's designs, drawn at random in the box (numpy seed 20261207:
    # L log-uniform, the pair uniform, the body's scale log-uniform in 0.5-2), solved for
    # the fresh sets N46-N53 only: the reversed pair on a softened Ecoflex body, a thick
    # membrane under PDMS 1:15, a short stiffened PDMS 1:10 body (the fourth draw: the
    # third, Ecoflex x 0.63 on Ecoflex, L 10.8 t 1.08 T 1.45 b 2.33 h 0.16, bent only 16-28
    # deg at the FE's 500 ul -- a balloon, no lab's actuator -- and was replaced before any
    # set of it was calibrated)
    "D26": dict(L_mm=14.9, t_mm=0.88, T_mm=1.09, b_mm=1.37, h_mm=0.19,
                body_material="ecoflex_00_30*0.89", membrane_material="pdms_1_15"),
    "D27": dict(L_mm=8.6, t_mm=1.15, T_mm=0.8, b_mm=2.01, h_mm=0.16,
                body_material="pdms_1_15*1.05", membrane_material="ecoflex_00_30"),
    "D28": dict(L_mm=5.0, t_mm=0.89, T_mm=0.83, b_mm=1.44, h_mm=0.15,
                body_material="pdms_1_10*1.76", membrane_material="ecoflex_00_30"),
    # the fiftieth session's designs, drawn at random in the box likewise (numpy seed
    # 20261208, the first three draws), solved for the fresh sets N54-N61 only: a long
    # shallow stiffened Ecoflex body on Ecoflex, a deep chamber under PDMS 1:10, a short
    # deep stiffened Ecoflex body on the PDMS 1:15 membrane (the reversed pair)
    "D29": dict(L_mm=15.9, t_mm=0.82, T_mm=1.03, b_mm=1.95, h_mm=0.13,
                body_material="ecoflex_00_30*1.32", membrane_material="ecoflex_00_30"),
    "D30": dict(L_mm=8.6, t_mm=0.77, T_mm=1.13, b_mm=1.82, h_mm=0.25,
                body_material="pdms_1_10*1.09", membrane_material="ecoflex_00_30"),
    "D31": dict(L_mm=4.8, t_mm=0.99, T_mm=1.49, b_mm=1.33, h_mm=0.28,
                body_material="ecoflex_00_30*1.66", membrane_material="pdms_1_15"),
}
# a specimen's FE solves with one layer's moduli scaled: cache suffix -> (layer, factor)
VARIANTS = {"_m1.1": ("membrane_material", 1.1), "_b1.12": ("body_material", 1.12),
            "_m0.9": ("membrane_material", 0.9)}
# a specimen's FE solves with its membrane thicker: cache suffix -> added thickness (mm)
THICKER = {"_t+0.08": 0.08}
T_FACTORS = {"a": 0.96, "b": 1.0, "c": 1.045}   # the specimens' membrane thickness
SPECIMENS = ["a", "b", "c"]
STATE = {1: "load", 0: "hold", -1: "unload"}
H_S = 0.002                                     # the integration grid of the effects

# name: design, flow rates (None: the nominal specimen to angle_target in the loading),
# reading interval (s), readings loading / holding / unloading, effect, seed, options
SETS = {
    "L1-clean-D1": ("D1", [2.5, 5.0], 1.0, 10, 0, 0, {}, 1, {}),
    "L2-clean-D2-hold": ("D2", [None], 2.0, 7, 3, 4, {}, 2, {}),
    "L3-membrane1.1-D3": ("D3", [None], 2.0, 7, 3, 4, {"kind": "membrane_x1.1"}, 3,
                          {"fe_suffix": "_m1.1"}),
    "L4-offset3-D4": ("D4", [None], 1.0, 10, 0, 0, {"kind": "angle_offset", "deg": 3.0}, 4, {}),
    "L5-air-D5": ("D5", [None], 3.0, 7, 3, 4, {"kind": "compliance", "C_ul_per_kpa": 3.0}, 5, {}),
    "L6-leak-D6": ("D6", [None], 1.0, 8, 6, 0, {"kind": "leak", "G_ul_s_per_kpa": 0.2}, 6, {}),
    "L7-relax-D7": ("D7", [None], 2.0, 6, 4, 4, {"kind": "relaxation", "g": 0.2, "tau_s": 3.0},
                    7, {"angle_target": 40}),
    "L8-tilt40-D2": ("D2", [None], 2.0, 7, 3, 4, {"kind": "tilted_camera", "phi_deg": 40}, 18, {}),
    "L8b-tilt40-soft-D2": ("D2", [None], 2.0, 7, 3, 4, {"kind": "tilted_camera", "phi_deg": 40},
                           8, {}),
    "L9-gauge60-D1": ("D1", [None], 2.0, 7, 3, 4, {"kind": "gauge_offset", "pa": 60}, 9,
                      {"fmt": "comma"}),
    # the forty-second session's sets, on designs the fixes were not made on
    "N1-clean-D8": ("D8", [None], 2.0, 7, 3, 4, {}, 21, {}),
    "N2-gauge60-D9": ("D9", [None], 2.0, 7, 3, 4, {"kind": "gauge_offset", "pa": 60}, 22, {}),
    "N3-membrane1.1-D10": ("D10", [None], 2.0, 7, 3, 4, {"kind": "membrane_x1.1"}, 23,
                           {"fe_suffix": "_m1.1"}),
    "N4-air-D8": ("D8", [None], 2.0, 7, 3, 4, {"kind": "compliance", "C_ul_per_kpa": 2.0},
                  24, {}),
    "N5-clean-D10": ("D10", [3.0], 1.5, 9, 0, 0, {}, 25, {"fmt": "comma"}),
    # the forty-third session's fresh sets, truths and seeds fixed before any calibration:
    # new lab habits (two specimens, fewer readings, an unload without a hold, mbar, psi,
    # ms, a fast and a slow pump)
    "N6-clean-D11": ("D11", [None], 2.0, 7, 3, 4, {}, 31,
                     {"specimens": 2, "p_unit": "mbar", "t_unit": "ms"}),
    "N7-batch1.08-D12": ("D12", [None], 2.0, 5, 0, 3, {"kind": "batch", "scale": 1.08}, 32,
                         {"p_unit": "psi"}),
    "N8-body1.12-D11": ("D11", [None], 2.0, 7, 3, 4, {"kind": "body_x1.12"}, 33,
                        {"fe_suffix": "_b1.12"}),
    # 0.25 m of 0.5 mm bore tubing, water (1 mPa s): R = 128 mu l / (pi d^4), 163 Pa per
    # ul/s; the loading in 3 s (a fast pump), then the unloading without a hold
    "N9-inlet-fast-D13": ("D13", [None], 0.5, 6, 0, 4,
                          {"kind": "inlet", "R_pa_per_ul_s": 163.0}, 34, {"t_unit": "ms"}),
    "N10-air+zero-D12": ("D12", [None], 2.0, 7, 3, 4,
                         {"kind": "compliance+gauge_offset", "C_ul_per_kpa": 2.5, "pa": 40},
                         35, {"p_unit": "mbar"}),
    "N11-leak-slow-D11": ("D11", [None], 4.0, 12, 4, 3, {"kind": "leak", "G_ul_s_per_kpa": 0.08},
                          36, {"p_unit": "psi"}),
    "N12-relax-D13": ("D13", [None], 2.0, 7, 4, 4, {"kind": "relaxation", "g": 0.25,
                                                    "tau_s": 4.0}, 37, {}),
    # outside the catalogue: the camera's time stamps 0.5 s late against the pump's log
    # (each frame shows the actuator 0.5 s before its stamp)
    "N13-camera-lag-D12": ("D12", [None], 1.0, 10, 4, 6, {"kind": "camera_lag", "s": 0.5}, 38,
                           {"fmt": "comma"}),
    # the forty-fifth session's fresh sets, truths and seeds fixed before any calibration:
    # new lab habits (readings every 0.5 s, hPa, inH2O, one specimen run four times, a
    # loading without an unloading, a hold of 30 s)
    "N14-clean-D15": ("D15", [None], 0.5, 20, 6, 12, {}, 41, {"p_unit": "hPa"}),
    "N15-membrane0.9-D14": ("D14", [None], 2.0, 7, 3, 4, {"kind": "membrane_x0.9"}, 42,
                            {"fe_suffix": "_m0.9", "p_unit": "inH2O"}),
    # the loading in 4 s, then a hold of 30 s read every second, then the unloading
    "N16-leak-fast-hold30-D16": ("D16", [None], 1.0, 4, 30, 4,
                                 {"kind": "leak", "G_ul_s_per_kpa": 0.1}, 43, {}),
    # one specimen run four times (a `run` column 1-4), its gauge's zero 45 Pa low
    "N17-zero-one-specimen-D15": ("D15", [None] * 4, 2.0, 7, 3, 4,
                                  {"kind": "gauge_offset", "pa": -45}, 44, {"specimens": 1}),
    # a slow pump (the loading in 50 s) read every 5 s, loading only
    "N18-air-slow-load-only-D14": ("D14", [None], 5.0, 10, 0, 0,
                                   {"kind": "compliance", "C_ul_per_kpa": 3.0}, 45, {}),
    "N19-membrane0.9+offset-D14": ("D14", [None], 2.0, 7, 3, 4,
                                   {"kind": "membrane_x0.9+angle_offset", "deg": 2.0}, 46,
                                   {"fe_suffix": "_m0.9", "fmt": "comma"}),
    # outside the catalogue: Mullins softening, the pressure below the loading curve's by
    # m (1 - V / V_max so far) wherever the chamber holds less than it held before (the
    # unloading); the shape at a volume unchanged (both layers alike)
    "N20-mullins-D15": ("D15", [None], 2.0, 7, 3, 4, {"kind": "mullins", "m": 0.3}, 47, {}),
    # an inlet of 120 Pa per ul/s and the mount tilted -2 deg, a fast pump read every 0.5 s
    "N21-inlet+offset-fast-D16": ("D16", [None], 0.5, 8, 2, 6,
                                  {"kind": "inlet+angle_offset", "R_pa_per_ul_s": 120.0,
                                   "deg": -2.0}, 48, {"p_unit": "hPa"}),
    # the forty-sixth session's fresh sets, truths and seeds fixed before any calibration:
    # new lab habits (angles in radians, the pump's volume in ml, a units row under the
    # header, a staircase of holds, two flow rates in one file, time as mm:ss text, a wide
    # layout with one column per specimen, 4 readings a curve on 2 specimens, mmHg, a
    # volume log without time)
    "N22-clean-reversed-D17": ("D17", [None], 2.0, 7, 3, 4, {}, 51,
                               {"a_unit": "rad", "v_unit": "ml"}),
    # a spin-coated membrane batch 0.08 mm thicker than drawn (its FE solves)
    "N23-membrane-thicker-D18": ("D18", [None], 2.0, 7, 3, 4, {"kind": "membrane_thicker"}, 52,
                                 {"fe_suffix": "_t+0.08", "units_row": True}),
    # the gauge's zero running away at +4 Pa/s; the pump in three steps, each held 6 s
    "N24-drift-staircase-D19": ("D19", [None], 2.0, 0, 0, 0,
                                {"kind": "gauge_drift", "pa_per_s": 4.0}, 53,
                                {"program": [(1, 3), (0, 3), (1, 3), (0, 3), (1, 3), (0, 3),
                                             (-1, 6)]}),
    # 1 m of soft 0.5 mm bore tubing: an inlet of 100 Pa per ul/s and 2 ul/kPa of
    # compliance; the same specimens at two flow rates (3 ul/s and 1 ul/s), time in ms
    "N25-inlet+air-two-flows-D17": ("D17", [3.0, 1.0], 1.0, 10, 3, 5,
                                    {"kind": "compliance+inlet", "C_ul_per_kpa": 2.0,
                                     "R_pa_per_ul_s": 100.0}, 54, {"t_unit": "ms"}),
    # outside the catalogue: a lamp warming the rig, both layers' moduli x (1 - 0.0006 per
    # s of the session); the three specimens run twice in turn (S1, S2, S3, S1, ...) with
    # 30 s between curves; time written as mm:ss text
    "N26-warming-session-D18": ("D18", [None, None], 2.0, 7, 3, 4,
                                {"kind": "session_drift", "per_s": -0.0006, "gap_s": 30.0},
                                55, {"t_fmt": "mmss"}),
    # creep of the silicone (g 0.2, tau 4 s) in a wide layout: one row per time, a
    # pressure and an angle column per specimen
    "N27-creep-wide-D19": ("D19", [None], 2.0, 7, 4, 5,
                           {"kind": "creep", "g": 0.2, "tau_s": 4.0}, 56, {"layout": "wide"}),
    # the mount tilted +2.5 deg; 2 specimens read at 4 points each (rest and 3 loading)
    "N28-offset-few-points-D17": ("D17", [None], 3.0, 3, 0, 0,
                                  {"kind": "angle_offset", "deg": 2.5}, 57, {"specimens": 2}),
    # the angle tool's scale 7 % short (angle x 0.93) and the gauge's zero 50 Pa low; the
    # pump's volume log in ml and no time, pressures in mmHg
    "N29-camera-gain+zero-volume-only-D18": ("D18", [None], 2.0, 7, 3, 4,
                                             {"kind": "camera_gain+gauge_offset", "k": 0.93,
                                              "pa": -50}, 58,
                                             {"v_unit": "ml", "no_time_flow": True,
                                              "p_unit": "mmHg"}),
    # the forty-seventh session's fresh sets, truths and seeds fixed before any
    # calibration: new lab habits (an instrument's preamble above the header, a date
    # column with the gauge re-zeroed each day, a tab-separated export with decimal
    # commas, the flow in ul/min and the time in min, two flow rates with angles in
    # radians, a hold staircase, psi)
    # a clean set at lab realism: 5 readings loading, 2 held, 4 unloading, every 3 s; the
    # logger's two lines of text above the header
    "N30-clean-preamble-D20": ("D20", [None], 3.0, 5, 2, 4, {}, 61, {"preamble": True}),
    # a membrane batch 10 % stiffer (its FE solves); the specimens measured on three days,
    # the gauge re-zeroed each morning (its zero -30, +10, +35 Pa), a date column;
    # loaded to 60 deg (the thickest specimen's FE solve ends at 64 deg)
    "N31-membrane1.1-days-D21": ("D21", [None], 2.0, 7, 3, 4,
                                 {"kind": "membrane_x1.1+day_zero",
                                  "zeros_pa": [-30.0, 10.0, 35.0]}, 62,
                                 {"fe_suffix": "_m1.1", "dates": True, "angle_target": 60}),
    # a pinhole leak G 0.12 ul/s per kPa; the pump in two steps each held 4 readings;
    # the flow in ul/min, the time in min
    "N32-leak-staircase-D22": ("D22", [None], 2.0, 0, 0, 0,
                               {"kind": "leak", "G_ul_s_per_kpa": 0.12}, 63,
                               {"program": [(1, 4), (0, 4), (1, 4), (0, 4), (-1, 6)],
                                "q_unit": "ul/min", "t_unit": "min"}),
    # the gauge's zero running away at -3 Pa/s; a LabVIEW-style tab-separated export with
    # decimal commas, pressures in mbar
    "N33-drift-tabs-D21": ("D21", [None], 2.0, 7, 3, 4,
                           {"kind": "gauge_drift", "pa_per_s": -3.0}, 64,
                           {"fmt": "tab", "p_unit": "mbar"}),
    # air in the line (C 2.5 ul/kPa) and the mount tilted -1.5 deg; the specimens at
    # 2 and 5 ul/s in one file, angles in radians
    "N34-air+offset-two-flows-rad-D22": ("D22", [2.0, 5.0], 1.0, 10, 3, 6,
                                         {"kind": "compliance+angle_offset",
                                          "C_ul_per_kpa": 2.5, "deg": -1.5}, 65,
                                         {"a_unit": "rad"}),
    # outside the catalogue: a gauge whose calibration errs quadratically, p_read = p +
    # k p^2 (k 4e-5 per Pa: +10 Pa at 0.5 kPa, +78 Pa at D20's top, 1.4 kPa: 5.6 %)
    "N35-gauge-quadratic-D20": ("D20", [None], 2.0, 7, 3, 4,
                                {"kind": "gauge_quadratic", "k_per_pa": 4e-5}, 66, {}),
    # outside the catalogue: a rim that opens above a pressure, dV_lost/dt = G (p -
    # p_open) where p > p_open (G 0.8 ul/s per kPa above 4 kPa, D21's top at 5.1 kPa);
    # a hold of 8 s at the top
    "N36-leak-above-D21": ("D21", [None], 1.0, 8, 8, 6,
                           {"kind": "leak_above", "G_ul_s_per_kpa": 0.8, "p_open_pa": 4000.0},
                           67, {}),
    # pressure relaxation of the silicone (g 0.2, tau 3 s), pressures in psi
    "N37-relax-psi-D20": ("D20", [None], 1.5, 8, 4, 5,
                          {"kind": "relaxation", "g": 0.2, "tau_s": 3.0}, 68, {"p_unit": "psi"}),
    # the forty-eighth session's fresh sets, truths and seeds fixed before any
    # calibration: new lab habits (a logger's timestamp column, ISO, day/month/year or
    # epoch seconds; the pressure's unit after a space, 'Pressure kPa'; the specimens told
    # apart by a 'Sample' column; semicolons, decimal commas and trailing empty columns)
    # a clean set at lab realism: 5 readings loading, 2 held, 4 unloading, every 3 s; the
    # logger's ISO timestamp the only time axis (no time column)
    "N38-clean-timestamp-D23": ("D23", [None], 3.0, 5, 2, 4, {}, 71,
                                {"stamp": "iso", "no_time": True}),
    # a membrane batch 10 % softer (its FE solves); the pressure's header 'Pressure kPa'
    "N39-membrane0.9-kpa-D23": ("D23", [None], 2.0, 7, 3, 4, {"kind": "membrane_x0.9"}, 72,
                                {"fe_suffix": "_m0.9", "p_header": "space"}),
    # a pinhole leak G 0.15 ul/s per kPa with a 12 s hold; the specimens told apart by a
    # 'Sample' column (no curve_id)
    "N40-leak-sample-column-D24": ("D24", [None], 2.0, 6, 6, 4,
                                   {"kind": "leak", "G_ul_s_per_kpa": 0.15}, 73,
                                   {"id_col": "Sample"}),
    # a narrow inlet, 140 Pa per ul/s, a fast pump read every 0.5 s; German Excel's ';'
    # and decimal commas with two empty columns at the end of every line
    "N41-inlet-trailing-D25": ("D25", [None], 0.5, 8, 2, 6,
                               {"kind": "inlet", "R_pa_per_ul_s": 140.0}, 74, {"trailing": 2}),
    # the angle tool's scale 8 % short and the gauge's zero running away at +3 Pa/s; a
    # 'Date' column, day/month/year and the time of day, beside the time column
    "N42-gain+drift-date-D24": ("D24", [None], 2.0, 7, 3, 4,
                                {"kind": "camera_gain+gauge_drift", "k": 0.92,
                                 "pa_per_s": 3.0}, 75, {"stamp": "dmy"}),
    # pressure relaxation (g 0.25, tau 5 s) and the mount tilted -2 deg; an epoch-seconds
    # column beside the time column, comma-separated
    "N43-relax+offset-epoch-D25": ("D25", [None], 1.5, 8, 4, 5,
                                   {"kind": "relaxation+angle_offset", "g": 0.25,
                                    "tau_s": 5.0, "deg": -2.0}, 76,
                                   {"stamp": "epoch", "fmt": "comma"}),
    # outside the catalogue: Mullins softening after the first loading only, each specimen
    # loaded twice (runs 1 and 2): the pressure x (1 - m (1 - V / V_max so far)), V_max
    # counted over both runs, so the first loading is the virgin curve and everything
    # after it (its unloading, the second run) is softer; the shape at a volume unchanged
    "N44-mullins-first-loading-D23": ("D23", [None, None], 2.0, 7, 3, 4,
                                      {"kind": "mullins_first", "m": 0.25}, 77, {}),
    # outside the catalogue: an angle sensor that saturates, reading no more than 60 deg
    # of bend (its stop) while the actuator bends to 75 deg
    "N45-angle-saturates-D25": ("D25", [None], 2.0, 7, 3, 4,
                                {"kind": "angle_saturation", "max_deg": 60.0}, 78, {}),
    # the forty-ninth session's fresh sets, truths and seeds fixed before any calibration:
    # new lab habits (a blank line between specimens, the columns in another order, a
    # logger's extra columns -- the rig's temperature and an operator's note)
    # a clean set, few points (6 loading, 2 held, 4 unloading every 2 s); a blank line
    # after each specimen's block, the columns in another order
    "N46-clean-blank-lines-D26": ("D26", [None], 2.0, 6, 2, 4, {}, 81,
                                  {"blank_lines": True, "order": "shuffled"}),
    # a clean set at lab realism, every 3 s; the logger's extra columns (temperature,
    # a note), comma-separated
    "N47-clean-extra-columns-D27": ("D27", [None], 3.0, 5, 2, 4, {}, 82,
                                    {"extra": True, "fmt": "comma"}),
    # the mount tilted +1 deg (small: 1.4 x the camera's 0.7 deg noise); ';' and decimal
    # commas with a blank line after each specimen
    "N48-offset1-small-D28": ("D28", [None], 2.0, 7, 3, 4, {"kind": "angle_offset", "deg": 1.0},
                              83, {"blank_lines": True}),
    # a membrane batch 10 % stiffer (its FE solves); the columns in another order
    "N49-membrane1.1-order-D27": ("D27", [None], 2.0, 7, 3, 4, {"kind": "membrane_x1.1"}, 84,
                                  {"fe_suffix": "_m1.1", "order": "shuffled"}),
    # a narrow inlet, 80 Pa per ul/s, a fast pump read every 0.5 s; pressures in mbar
    "N50-inlet80-fast-D26": ("D26", [None], 0.5, 8, 2, 6,
                             {"kind": "inlet", "R_pa_per_ul_s": 80.0}, 85, {"p_unit": "mbar"}),
    # outside the catalogue: a gauge that lags the pressure (a damped gauge, or a long thin
    # line to it: its reading relaxes to the pressure with tau 1.5 s), read every second:
    # low while the pump loads, high while it withdraws
    "N51-gauge-lag-D28": ("D28", [None], 1.0, 10, 3, 6, {"kind": "gauge_lag", "tau_s": 1.5},
                          86, {}),
    # an angle sensor at its stop (45 deg) that reads exactly its stop there (its noise
    # clipped too), while the actuator bends to 75
    "N52-angle-pinned45-D27": ("D27", [None], 2.0, 7, 3, 4,
                               {"kind": "angle_saturation", "max_deg": 45.0, "pinned": True},
                               87, {}),
    # the gauge's zero 30 Pa high (small: the gauge's 1.5 % + 2 Pa noise is 15-40 Pa at
    # the top); a tab-separated export with decimal commas and the logger's extra columns
    "N53-gauge30-small-extra-D26": ("D26", [None], 2.0, 7, 3, 4,
                                    {"kind": "gauge_offset", "pa": 30}, 88,
                                    {"extra": True, "fmt": "tab"}),
    # the fiftieth session's fresh sets, truths and seeds fixed before any calibration:
    # new lab habits (units in square brackets with a degree sign and a micro sign, a
    # byte-order mark with every decimal comma quoted in a comma-separated export,
    # Windows-1252 text, a logger's line of text after the last reading)
    # a clean set at lab realism, every 3 s; headers 'Time [s]', 'Flow [µl/s]',
    # 'Pressure [kPa]', 'Angle [°]'
    "N54-clean-brackets-D29": ("D29", [None], 3.0, 5, 2, 4, {}, 91, {"units": "brackets"}),
    # a clean set, few points, no hold; a spreadsheet's comma-separated export in a
    # decimal-comma locale (each number with a comma quoted), a UTF-8 byte-order mark and
    # a blank line after each specimen
    "N55-clean-quoted-bom-D30": ("D30", [None], 2.0, 6, 0, 5, {}, 92,
                                 {"fmt": "quoted", "bom": True, "blank_lines": True}),
    # air in the line, C 0.8 ul/kPa (small: about 4 % of the volume at the top of the
    # reversed pair's 5 kPa); pressures in mbar
    "N56-air-small-D31": ("D31", [None], 2.0, 7, 3, 4,
                          {"kind": "compliance", "C_ul_per_kpa": 0.8}, 93, {"p_unit": "mbar"}),
    # outside the catalogue: a dial gauge's dead band (friction in its movement: the
    # pointer moves only once the pressure is 40 Pa away from where it stands), reading
    # low while the pressure rises and high while it falls -- the opposite sign of an
    # inlet's R Q
    "N57-gauge-deadband-D29": ("D29", [None], 2.0, 7, 3, 4,
                               {"kind": "gauge_deadband", "pa": 40.0}, 94, {}),
    # a pinhole leak G 0.2 ul/s per kPa with no hold: the loading at a steady pace, the
    # unloading straight after -- the chamber empties before the pump does, which the
    # unloading branch shows; the columns in another order
    "N58-leak-no-hold-D30": ("D30", [None], 1.0, 8, 0, 8,
                             {"kind": "leak", "G_ul_s_per_kpa": 0.2}, 95,
                             {"order": "shuffled"}),
    # the mount tilted -2.5 deg; Windows-1252 text, 'Flow (µl/s)' and 'Angle (°)'
    "N59-offset-cp1252-D31": ("D31", [None], 2.0, 7, 3, 4, {"kind": "angle_offset", "deg": -2.5},
                              96, {"encoding": "cp1252", "units": "symbols"}),
    # the gauge's zero running away at +3 Pa/s with a 12 s hold; time in ms, the logger's
    # line after the last reading
    "N60-drift-footer-D29": ("D29", [None], 2.0, 6, 6, 4,
                             {"kind": "gauge_drift", "pa_per_s": 3.0}, 97,
                             {"footer": True, "t_unit": "ms"}),
    # pressure relaxation (g 0.2, tau 3 s), each specimen run twice; comma-separated
    "N61-relax-two-runs-D30": ("D30", [None, None], 2.0, 7, 4, 4,
                               {"kind": "relaxation", "g": 0.2, "tau_s": 3.0}, 98,
                               {"fmt": "comma"}),
}
# the pressure and time units a lab writes: unit -> (per Pa or per s, decimals)
PRESSURE_UNITS = {"kPa": (1e-3, 3), "mbar": (1e-2, 2), "psi": (1 / 6894.757293168361, 4),
                  "hPa": (1e-2, 2), "inH2O": (1 / 249.08891, 3),
                  "mmHg": (1 / 133.322387415, 3)}
TIME_UNITS = {"s": (1.0, 1), "ms": (1e3, 0), "min": (1 / 60, 4)}
FLOW_UNITS = {"ul/s": (1.0, 2), "ul/min": (60.0, 1)}
# a logger's timestamp column: kind -> its header; the session starts 2026-12-07 14:03:11
STAMP_HEADERS = {"iso": "Timestamp", "dmy": "Date", "epoch": "Epoch (s)"}
SESSION_START = 1796652191.0      # 2026-12-07T14:03:11 UTC in epoch seconds


def logger_stamp(kind: str, session_s: float) -> str:
    """A reading's time stamp as a logger writes it: ISO 8601, day/month/year and the time
    of day (to the second), or epoch seconds (to 0.1 s)."""
    import datetime as dt
    when = dt.datetime.fromtimestamp(SESSION_START + session_s, dt.UTC)
    if kind == "epoch":
        return f"{SESSION_START + session_s:.1f}"
    return when.strftime("%Y-%m-%dT%H:%M:%S" if kind == "iso" else "%d/%m/%Y %H:%M:%S")


# the field separator and the decimal mark: German Excel's, English, a tab-separated export
FORMATS = {"semicolon": (";", ","), "comma": (",", "."), "tab": ("\t", ","),
           "quoted": (",", ",")}
# how the measured columns' headers carry their units: habit -> (open, close, flow unit's
# 'u', the angle's unit)
UNIT_STYLES = {"parentheses": ("(", ")", "u", "deg"), "brackets": ("[", "]", "µ", "°"),
               "symbols": ("(", ")", "µ", "°")}
# the sets tests/test_calibration_history.py, test_calibration_gauge_zero.py,
# test_calibration_exact_alike.py, test_calibration_lab_fresh.py and
# test_calibration_lab_s45.py, _s46.py, _s47.py and _s48.py read, with the pump's log
TEST_DATA = {"flat_top_two_flows": "L1-clean-D1", "hold_at_a_flat_top": "L8b-tilt40-soft-D2",
             "leak_in_a_hold": "L6-leak-D6", "gauge_zero_off": "L9-gauge60-D1",
             "gauge_zero_off_soft_batch": "N2-gauge60-D9",
             "inlet_fast_unload": "N9-inlet-fast-D13", "camera_late": "N13-camera-lag-D12",
             "body_stiffer": "N8-body1.12-D11", "leak_slow_pump": "N11-leak-slow-D11",
             "membrane_softer_inh2o": "N15-membrane0.9-D14",
             "inlet_tilted_fast": "N21-inlet+offset-fast-D16",
             "flat_top_hold_reversed": "N22-clean-reversed-D17",
             "staircase_drift": "N24-drift-staircase-D19",
             "units_row": "N23-membrane-thicker-D18", "clock_time": "N26-warming-session-D18",
             "one_column_per_specimen": "N27-creep-wide-D19",
             "offset_two_specimens_four_points": "N28-offset-few-points-D17",
             "gauge_zero_volume_log": "N29-camera-gain+zero-volume-only-D18",
             "inlet_air_two_flows": "N25-inlet+air-two-flows-D17",
             "text_above_header": "N30-clean-preamble-D20",
             "air_tilt_two_flows_rad": "N34-air+offset-two-flows-rad-D22",
             "timestamp_only": "N38-clean-timestamp-D23",
             "pressure_unit_after_space": "N39-membrane0.9-kpa-D23",
             "sample_column": "N40-leak-sample-column-D24",
             "date_beside_time": "N42-gain+drift-date-D24",
             "epoch_beside_time": "N43-relax+offset-epoch-D25",
             "first_loading_stiffer": "N44-mullins-first-loading-D23",
             "angle_sensor_stops": "N45-angle-saturates-D25",
             "angle_sensor_pinned": "N52-angle-pinned45-D27",
             "logger_extra_columns": "N47-clean-extra-columns-D27",
             "blank_lines_other_order": "N46-clean-blank-lines-D26",
             "gauge_zero_small_tabs": "N53-gauge30-small-extra-D26",
             "quoted_decimal_commas_bom": "N55-clean-quoted-bom-D30",
             "text_after_the_readings": "N60-drift-footer-D29"}


def solve_missing(cache: Path, names: list[str] | None = None) -> None:
    """FE-solve every specimen the sets ``names`` (default: all) use that ``cache`` lacks
    (one .npz a solve)."""
    from solver import Design, SolverSettings, solve

    cache.mkdir(parents=True, exist_ok=True)
    used = [SETS[n] for n in names] if names else list(SETS.values())
    jobs = sorted({(v[0], k, "") for v in used for k in T_FACTORS})
    jobs += sorted({(v[0], k, v[8]["fe_suffix"]) for v in used
                    if v[8].get("fe_suffix") for k in T_FACTORS})  # one layer stiffer
    for d, k, suffix in jobs:
        path = cache / f"{d}{k}{suffix}.npz"
        if path.exists():
            continue
        kw = dict(DESIGNS[d], t_mm=round(DESIGNS[d]["t_mm"] * T_FACTORS[k], 4))
        if suffix in THICKER:
            kw["t_mm"] = round((DESIGNS[d]["t_mm"] + THICKER[suffix]) * T_FACTORS[k], 4)
        elif suffix:
            layer, factor = VARIANTS[suffix]
            preset, _, scale = kw[layer].partition("*")
            kw[layer] = f"{preset}*{round(float(scale or 1) * factor, 6):g}"
        c = solve(Design(**kw), SolverSettings())
        np.savez(path, pressure_pa=c.pressure_pa, volume_ul=c.volume_ul,
                 angle_deg=c.angle_deg, status=c.status, design=json.dumps(kw))
        print(path.name, c.status, f"{c.angle_deg[-1]:.1f} deg at {c.volume_ul[-1]:.1f} ul",
              flush=True)


def fe_curve(cache: Path, name: str) -> dict:
    """The FE curve's pressure and angle as smooth functions of the injected volume."""
    z = np.load(cache / f"{name}.npz")
    v, p, a = z["volume_ul"], z["pressure_pa"], z["angle_deg"]
    keep = np.concatenate([[True], np.diff(v) > 1e-9])
    return dict(p=PchipInterpolator(v[keep], p[keep]), a=PchipInterpolator(v[keep], a[keep]),
                vmax=float(v[keep][-1]))


def volume_at_angle(c: dict, angle_deg: float) -> float:
    vv = np.linspace(0, c["vmax"], 4000)
    aa = np.abs(c["a"](vv))
    return float(vv[np.argmax(aa >= angle_deg)]) if aa[-1] >= angle_deg else c["vmax"]


def pump_volume(t: np.ndarray, q: float, dt: float, n_load: int, n_hold: int) -> np.ndarray:
    """The syringe's volume (ul) at times t: in at q, stopped, withdrawn at q."""
    t_load, t_hold = n_load * dt, (n_load + n_hold) * dt
    return np.where(t <= t_load, q * t, np.where(
        t <= t_hold, q * t_load, np.maximum(q * t_load - q * (t - t_hold), 0.0)))


def pump_volume_program(t: np.ndarray, q: float, dt: float,
                        program: list[tuple[int, int]]) -> np.ndarray:
    """The syringe's volume (ul) at times t for a program of (direction, readings) steps:
    in at q (+1), stopped (0), withdrawn at q (-1), never below empty."""
    rate = np.zeros_like(t)
    start = 0.0
    for direction, count in program:
        rate[(t > start) & (t <= start + count * dt)] = direction * q
        start += count * dt
    v = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t))])
    return np.maximum(v, 0.0)


def chamber(c: dict, s: float, vp: np.ndarray, effect: dict) -> tuple[np.ndarray, np.ndarray]:
    """The chamber's volume and pressure on the 2 ms grid for the pump's volume vp."""
    def p_of(v):
        return s * c["p"](np.clip(v, 0, c["vmax"]))
    kinds = effect.get("kind", "").split("+")
    vch = vp.copy()
    if "compliance" in kinds:       # air in the line: V_pump = V_ch + C p_ch
        for i, v in enumerate(vp):
            lo, hi = 0.0, v
            for _ in range(50):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if mid + effect["C_ul_per_kpa"] * p_of(mid) / 1000 > v \
                    else (mid, hi)
            vch[i] = 0.5 * (lo + hi)
    if "leak" in kinds:                          # a laminar pinhole: dV_lost/dt = G p_ch
        g, lost = effect["G_ul_s_per_kpa"], 0.0
        for i in range(1, vp.size):
            k1 = g * p_of(vp[i - 1] - lost) / 1000
            k2 = g * p_of(vp[i] - lost - H_S * k1) / 1000
            lost = min(lost + 0.5 * H_S * (k1 + k2), vp[i])
            vch[i] = vp[i] - lost
    if "leak_above" in kinds:                    # a rim that opens above p_open
        g, p_open, lost = effect["G_ul_s_per_kpa"], effect["p_open_pa"], 0.0
        for i in range(1, vp.size):
            k1 = g * max(p_of(vp[i - 1] - lost) - p_open, 0.0) / 1000
            k2 = g * max(p_of(vp[i] - lost - H_S * k1) - p_open, 0.0) / 1000
            lost = min(lost + 0.5 * H_S * (k1 + k2), vp[i])
            vch[i] = vp[i] - lost
    p = p_of(vch)
    if "mullins" in kinds:                       # softer below the volume held before
        p = p * (1 - effect["m"] * (1 - vch / np.maximum(np.maximum.accumulate(vch), 1e-12)))
    if "mullins_first" in kinds:                 # softer below the most held, runs before too
        held = np.maximum(np.maximum.accumulate(vch), effect.get("v_before", 0.0))
        p = p * (1 - effect["m"] * (1 - vch / np.maximum(held, 1e-12)))
    if "relaxation" in kinds:                    # a standard linear solid at a held volume
        y = np.zeros_like(p)
        for i in range(1, p.size):
            y[i] = y[i - 1] + H_S * (p[i - 1] - y[i - 1]) / effect["tau_s"]
        p = (1 + effect["g"]) * p - effect["g"] * y
    return vch, p


def readings(c: dict, s: float, q: float, dt: float, n: tuple[int, int, int],
             rng: np.random.Generator, effect: dict) -> dict:
    """One curve as the camera and the gauge read it, from rest at t = 0."""
    program = effect.get("program")
    states = ([d for d, k in program for _ in range(k)] if program
              else [1] * n[0] + [0] * n[1] + [-1] * n[2])
    t = dt * np.arange(len(states) + 1)
    fine = np.arange(0, t[-1] + H_S / 2, H_S)
    kinds = effect.get("kind", "").split("+")
    vp = (pump_volume_program(fine, q, dt, program) if program
          else pump_volume(fine, q, dt, n[0], n[1]))
    vch, p = chamber(c, s, vp, effect)
    a = c["a"](np.clip(vch, 0, c["vmax"]))
    if "session_drift" in kinds:                 # both layers' moduli drift with the session
        p = p * (1 + effect["per_s"] * (effect["t0_s"] + fine))
    if "creep" in kinds:                         # the bend creeps: a standard linear solid
        y = np.zeros_like(a)
        for i in range(1, a.size):
            y[i] = y[i - 1] + H_S * (a[i - 1] - y[i - 1]) / effect["tau_s"]
        a = (1 - effect["g"]) * a + effect["g"] * y
    if "inlet" in kinds:                         # the gauge at the pump: R times the flow
        flow = np.concatenate([[0.0], np.diff(vp) / H_S])    # just before each stamp
        p = p + effect["R_pa_per_ul_s"] * flow
    if "gauge_deadband" in kinds:                # the pointer moves once h Pa away
        y, h = np.zeros_like(p), effect["pa"]
        for i in range(1, p.size):
            y[i] = min(max(y[i - 1], p[i] - h), p[i] + h)
        p = y
    if "gauge_lag" in kinds:                     # the gauge relaxing to the pressure
        y = np.zeros_like(p)
        for i in range(1, p.size):
            y[i] = y[i - 1] + H_S * (p[i - 1] - y[i - 1]) / effect["tau_s"]
        p = y
    if "camera_lag" in kinds:                    # each frame shows the bend s earlier
        a = np.concatenate([np.zeros(round(effect["s"] / H_S)), a])[:a.size]
    idx = np.round(t / H_S).astype(int)
    p, a, v_pump = p[idx], a[idx], vp[idx]
    if "gauge_drift" in kinds:                   # the gauge's zero running away
        p = p + effect["pa_per_s"] * t
    if "camera_gain" in kinds:                   # the angle tool's scale off
        a = a * effect["k"]
    if "angle_offset" in kinds:                  # the mount tilted
        a = a + effect["deg"]
    if "tilted_camera" in kinds:                 # the bending plane seen at phi
        phi = math.radians(effect["phi_deg"])
        a = np.degrees(np.arctan2(np.sin(np.radians(a)) * math.cos(phi), np.cos(np.radians(a))))
    if "angle_saturation" in kinds and not effect.get("pinned"):   # the sensor at its stop
        a = np.clip(a, -effect["max_deg"], effect["max_deg"])
    if "gauge_offset" in kinds:
        p = p + effect["pa"]
    if "gauge_quadratic" in kinds:               # the gauge's calibration curved
        p = p + effect["k_per_pa"] * p ** 2
    if "day_zero" in kinds:                      # the gauge re-zeroed on each day
        p = p + effect["zero_pa"]
    zero = rng.normal(0, 3)
    p = p + zero + rng.normal(0, 1, t.size) * (0.015 * np.abs(p) + 2.0)
    a = a + rng.normal(0, 0.7, t.size)
    if "angle_saturation" in kinds and effect.get("pinned"):   # reads its stop exactly
        a = np.clip(a, -effect["max_deg"], effect["max_deg"])
    return dict(t=t, state=[1, *states], p=p, a=a, q=q, v=v_pump)


HABITS = ("a_unit", "v_unit", "units_row", "t_fmt", "layout", "no_time_flow")


def write_set(cache: Path, out: Path, name: str, file_name: str | None = None,
              with_pump: bool = False, note: str = "") -> Path:
    d, flows, dt, n_load, n_hold, n_unload, effect, seed, kw = SETS[name]
    rng = np.random.default_rng(seed)
    nominal = DESIGNS[d]
    suffix = kw.get("fe_suffix", "")
    stiff = {sp: float(np.clip(rng.normal(1, 0.07), 0.9, 1.1)) for sp in SPECIMENS}
    if effect.get("kind") == "batch":             # both layers' moduli x scale
        stiff = {sp: v * effect["scale"] for sp, v in stiff.items()}
    v_top = volume_at_angle(fe_curve(cache, f"{d}b{suffix}"), kw.get("angle_target", 75))
    p_unit, t_unit = kw.get("p_unit", "kPa"), kw.get("t_unit", "s")
    (p_per_pa, p_nd), (t_per_s, t_nd) = PRESSURE_UNITS[p_unit], TIME_UNITS[t_unit]
    program = kw.get("program")
    n_in = sum(k for way, k in program if way == 1) if program else n_load
    t_curve = dt * (sum(k for _, k in program) if program else n_load + n_hold + n_unload)
    rows, clock_s, n_curves = [], [], 0     # clock_s: each reading's second of the session
    for run, q in enumerate(flows, 1):
        for k, sp in enumerate(SPECIMENS[:kw.get("specimens", len(SPECIMENS))]):
            qq = v_top / (n_in * dt) if q is None else q
            session_s = (len(rows) // (round(t_curve / dt) + 1)) * (t_curve
                                                                     + effect.get("gap_s", 0))
            ef = dict(effect, program=program, t0_s=session_s) if program or (
                effect.get("kind") == "session_drift") else effect
            if "zeros_pa" in effect:             # the day's zero: one specimen a day
                ef = dict(ef, zero_pa=effect["zeros_pa"][k])
            if effect.get("kind") == "mullins_first" and run > 1:   # stretched before
                ef = dict(ef, v_before=v_top)
            r = readings(fe_curve(cache, f"{d}{sp}{suffix}"), stiff[sp], qq, dt,
                         (n_load, n_hold, n_unload), rng, ef)
            rows += [(f"S{k + 1}", run, r["t"][i] * t_per_s, qq, r["p"][i] * p_per_pa,
                      r["a"][i], STATE[r["state"][i]], r["v"][i]) for i in range(r["t"].size)]
            clock_s += [n_curves * (t_curve + 30.0) + x for x in r["t"]]   # 30 s apart
            n_curves += 1
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{file_name or name}.csv"
    if any(h in kw for h in HABITS):
        return write_habits(path, name, effect, nominal, rows, kw, api_json=not with_pump)
    sep, dec = FORMATS[kw.get("fmt", "semicolon")]
    q_unit = kw.get("q_unit", "ul/s")
    q_per_ul_s, q_nd = FLOW_UNITS[q_unit]
    geometry = ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm")
    dated = ["Date"] if kw.get("dates") else []
    stamp = kw.get("stamp")
    dated += [STAMP_HEADERS[stamp]] if stamp else []

    def day(cid: str, i: int = 0) -> list[str]:   # specimen S<k> measured on day k
        if stamp:
            return [logger_stamp(stamp, clock_s[i])]
        return [f"2026-12-0{cid[1:]}"] if dated else []
    timed = not kw.get("no_time")
    p_header = f"Pressure {p_unit}" if kw.get("p_header") == "space" else \
        f"Pressure ({p_unit})"
    trailing = [""] * kw.get("trailing", 0)
    extra = ["Temperature (C)", "Note"] if kw.get("extra") else []
    lu, ru, micro, degree = UNIT_STYLES[kw.get("units", "parentheses")]
    if kw.get("units") == "brackets":
        p_header = f"Pressure [{p_unit}]"
    flow_header = f"Flow {lu}{q_unit.replace('u', micro, 1)}{ru}"
    header = [kw.get("id_col", "curve_id"), "run", *dated, *geometry, "body_material",
              "membrane_material", *([f"Time {lu}{t_unit}{ru}"] if timed else []),
              flow_header, p_header, f"Angle {lu}{degree}{ru}", *extra] + (
        ["pump"] if with_pump else [])
    n_measured = 3 + timed
    first = header.index(flow_header) - timed
    # the columns in another order: the readings first (angle, pressure, flow, time),
    # then the rest as before
    order = (list(range(first + n_measured - 1, first - 1, -1))
             + [j for j in range(len(header)) if not first <= j < first + n_measured]
             if kw.get("order") == "shuffled" else list(range(len(header))))

    def num(x: float, nd: int) -> str:
        return f"{x:.{nd}f}".replace(".", dec)

    def logged(i: int, cid: str) -> list:        # a logger's extra columns: no reading
        return [num(22.4 + 0.01 * (i % 40), 1), "fresh specimen" if i == 0 or
                rows[i - 1][0] != cid else ""] if extra else []
    with open(path, "w", newline="", encoding=kw.get("encoding", "utf-8")) as fh:
        fh.write(("\ufeff" if kw.get("bom") else "")
                 + f"# {name}: {json.dumps(effect) if effect else 'no effect'}; made by "
                 f"benchmarks/lab_rig_sets.py from FE solves{note}\n")
        if kw.get("preamble"):                   # a logger's lines above its header
            fh.write("RigLogger 2.3 export, 2026-12-05 14:02\nSample batch 7, three "
                     "specimens\n")
        w = csv.writer(fh, delimiter=sep)
        w.writerow([header[j] for j in order] + trailing)
        for i, (cid, run, t, q, p_read, a, state, _) in enumerate(rows):
            row = [cid, run, *day(cid, i), *(num(nominal[g], 2) for g in geometry),
                   nominal["body_material"], nominal["membrane_material"],
                   *([num(t, t_nd)] if timed else []), num(q * q_per_ul_s, q_nd),
                   num(p_read, p_nd), num(a, 1), *logged(i, cid)] + (
                [state] if with_pump else [])
            w.writerow([row[j] for j in order] + trailing)
            if kw.get("blank_lines") and (i + 1 == len(rows) or rows[i + 1][:2] != (cid, run)):
                w.writerow([])                   # a blank line after each specimen's block
        if kw.get("footer"):                     # the logger's line after the last reading
            fh.write("Measurement stopped by user at 2026-12-08 14:22:05\r\n")
    if not with_pump:      # the API's body: the same rows, numbers as JSON numbers
        body = [dict(zip(header, [cid, run, *day(cid, i), *(nominal[g] for g in geometry),
                                  nominal["body_material"], nominal["membrane_material"],
                                  *([round(t, t_nd)] if timed else []),
                                  round(q * q_per_ul_s, q_nd), round(p_read, p_nd),
                                  round(a, 1), *(float(x.replace(dec, ".")) if k == 0 else x
                                                 for k, x in enumerate(logged(i, cid)))],
                         strict=True))
                for i, (cid, run, t, q, p_read, a, _, _) in enumerate(rows)]
        (out / f"{name}.json").write_text(json.dumps({"rows": body}))
    return path


def write_habits(path: Path, name: str, effect: dict, nominal: dict, rows: list,
                 kw: dict, api_json: bool = True) -> Path:
    """A set as a lab with other habits writes it (comma-separated, '.' decimals): angles
    in radians, the pump's volume in ml, no time or flow, time as mm:ss text, a units row
    under the header, or a wide layout (one row per time, a pressure and an angle column
    per specimen). The API's JSON rows (``api_json``) stay the long layout with units in
    the keys; tests/data's files (no pump column: their history is read) have none."""
    p_unit, t_unit = kw.get("p_unit", "kPa"), kw.get("t_unit", "s")
    p_nd, t_nd = PRESSURE_UNITS[p_unit][1], TIME_UNITS[t_unit][1]
    a_unit, v_unit = kw.get("a_unit", "deg"), kw.get("v_unit")
    timed = not kw.get("no_time_flow")
    geometry = ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm")

    def angle(a: float) -> float:
        return round(math.radians(round(a, 1)), 4) if a_unit == "rad" else round(a, 1)

    def clock(t: float) -> str:
        return f"{int(t // 60):02d}:{t % 60:04.1f}" if kw.get("t_fmt") == "mmss" \
            else f"{t:.{t_nd}f}"
    measured = ([f"Time ({t_unit})", "Flow (ul/s)"] if timed else []) + (
        [f"Volume ({v_unit})"] if v_unit else [])

    def values(t, q, v):
        return ([round(t, t_nd), round(q, 2)] if timed else []) + (
            [round(v / 1000, 4)] if v_unit else [])
    long_header = ["curve_id", "run", *geometry, "body_material", "membrane_material",
                   *measured, f"Pressure ({p_unit})", f"Angle ({a_unit})"]
    long_rows = [[cid, run, *(nominal[g] for g in geometry), nominal["body_material"],
                  nominal["membrane_material"], *values(t, q, v), round(p_read, p_nd),
                  angle(a)] for cid, run, t, q, p_read, a, _, v in rows]
    if api_json:
        (path.parent / f"{name}.json").write_text(json.dumps(
            {"rows": [dict(zip(long_header, r, strict=True)) for r in long_rows]}))
    with open(path, "w", newline="", encoding="utf-8") as fh:
        fh.write(f"# {name}: {json.dumps(effect) if effect else 'no effect'}; made by "
                 f"benchmarks/lab_rig_sets.py from FE solves\n")
        w = csv.writer(fh)
        if kw.get("layout") == "wide":           # one row per time, a column per specimen
            ids = sorted({r[0] for r in rows})
            w.writerow([*geometry, "body_material", "membrane_material", *measured,
                        *(f"{x} {cid} ({u})" for cid in ids
                          for x, u in (("Pressure", p_unit), ("Angle", a_unit)))])
            by_id = {cid: [r for r in rows if r[0] == cid] for cid in ids}
            for i, (_, _, t, q, _, _, _, v) in enumerate(by_id[ids[0]]):
                w.writerow([*(nominal[g] for g in geometry), nominal["body_material"],
                            nominal["membrane_material"], *values(t, q, v),
                            *(x for cid in ids for x in (round(by_id[cid][i][4], p_nd),
                                                         angle(by_id[cid][i][5])))])
            return path
        if kw.get("units_row"):                  # names, then a row of units under them
            w.writerow([h.split(" (")[0] if " (" in h else h for h in long_header])
            w.writerow(["", "", *("mm" for _ in geometry), "", "",
                        *(h.split(" (")[1].rstrip(")") for h in long_header[9:])])
        else:
            w.writerow([("Time (mm:ss)" if kw.get("t_fmt") == "mmss" and h == measured[0]
                         and timed else h) for h in long_header])
        for r, (_, _, t, *_rest) in zip(long_rows, rows, strict=True):
            if timed and kw.get("t_fmt") == "mmss":
                r = [*r[:9], clock(t), *r[10:]]
            w.writerow(r)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sets", nargs="*", help=f"some of {', '.join(SETS)} (default: all)")
    ap.add_argument("--cache", type=Path, required=True, help="FE curves (.npz), solved once")
    ap.add_argument("--out", type=Path, default=Path("lab-rig-sets"))
    ap.add_argument("--test-data", action="store_true",
                    help="write tests/data's 34 sets (those of them named, if any)")
    args = ap.parse_args()
    test_sets = [n for n in TEST_DATA.values() if not args.sets or n in args.sets]
    solve_missing(args.cache, test_sets if args.test_data else args.sets)
    if args.test_data:
        data = Path(__file__).resolve().parents[1] / "tests" / "data"
        for file_name, name in TEST_DATA.items():
            if name not in test_sets:
                continue
            print(write_set(args.cache, data, name, f"lab_gauge_noise_{file_name}", True,
                            ", the pump column its program"))
        return
    for name in args.sets or SETS:
        print(write_set(args.cache, args.out, name))


if __name__ == "__main__":
    main()
