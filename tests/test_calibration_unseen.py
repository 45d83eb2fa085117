"""The loop on measured data made the way other labs make them, from FE curves it was not
tuned on: records of the shipped database (service/data/curves.h5, read with the store
API; free tip, converged), at designs other than the test cases' (other L, t, T, b, h, the
reversed pair, PDMS 1:15 and Ecoflex bodies), with a lab protocol of its own (below), and
the mishaps labs make (kPa, radians, duplicated rows, a unit in a header, one specimen,
readings past the FE's range, no time or flow columns).

The generator (``lab_rows``) shares no code with tests/calibration_lab.py nor with the
fitting code's forms: a syringe pump fills the chamber at q ul/s for as long as it takes
to reach a target angle, holds, withdraws; a camera reads every ``read_s`` s (10 readings
while loading at the first flow rate, 5 at twice that); each specimen has its own
stiffness (chamber pressure at a volume x 1 + N(0, 3 %)) and amplitude (angle x 1 +
N(0, 2 %)); readings carry 0.5-0.9 deg angle noise and 4 Pa gauge noise, rounded as a
lab writes them (0.1 deg, 1 Pa). Truths act as the physics does:

* a stiffer or softer body is a database record whose body is the preset scaled by k
  (``pdms_1_15*k``): the lab calls it pdms_1_15, the truth is body_stiffness k;
* a stiffer or softer membrane is the same record read through the exact invariance of
  the hyperelastic problem (both layers' mu x s scale the pressure by s): the record's
  pressures / k are those of the nominal body on a membrane x 1/k;
* gauge and camera effects transform the readings; the inlet's drop R q d adds to the
  gauge while the pump runs; creep is a one-term Prony retardation of the FE's angle on a
  fine time grid;
* compliance (an air bubble: the chamber gets the pump's volume less C x pressure), in
  the catalogue since 2026-12-06 (line_compliance);
* outside the catalogue: a leak during the hold (volume lost at a rate proportional to
  the pressure), a rate-independent friction loop on unloading, a contact saturation.

``CASES`` pairs each data set with what a right answer is; ``judge`` says whether the
report gives it. ``benchmarks/calibration_cases.py --unseen`` prints the table and the
count; the cheap instructive cases run here, the rest are marked slow.
"""

from __future__ import annotations

import copy
import functools
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pytest

DB_PATH = Path(__file__).resolve().parents[1] / "service" / "data" / "curves.h5"
PRESSURE_NOISE_PA = 4.0


# Added to every protocol's seed: 0 in the tests; `benchmarks/calibration_cases.py --unseen
# --seed-offset 100` runs the same sets with other noise (seeds 107, 207 in RESULTS.md).
SEED_OFFSET = 0


@dataclass(frozen=True)
class Record:
    """One FE curve of the database, as a lab would name its design."""

    key: str
    body: str
    membrane: str
    scale: float          # the record's body mu scale (1 for a preset)
    design: dict
    pressure_pa: np.ndarray = field(repr=False)
    volume_ul: np.ndarray = field(repr=False)
    angle_deg: np.ndarray = field(repr=False)


@functools.cache
def _summaries() -> tuple[dict, ...]:
    """Every converged free-tip record of the shipped database with a preset membrane."""
    from solver.store.hdf5 import CurveStore

    with CurveStore(DB_PATH) as store:
        return tuple(s for s in store.summaries() if s["settings"]["tip"] == "free"
                     and s["status"] == "complete" and "*" not in s["design"]["membrane_material"])


@functools.cache
def _load(key: str) -> Record:
    from solver.store.hdf5 import CurveStore

    s = next(s for s in _summaries() if s["key"] == key)
    d = s["design"]
    body, _, k = d["body_material"].partition("*")
    with CurveStore(DB_PATH) as store:
        c = store.get(key).curve
    return Record(key, body, d["membrane_material"], float(k or 1.0), d,
                  np.asarray(c.pressure_pa, float), np.asarray(c.volume_ul, float),
                  np.asarray(c.angle_deg, float))


def record(body: str, membrane: str, scale: float = 1.0, **geometry: float) -> Record:
    """The record of this pair whose body scale and geometry are nearest the request."""
    def distance(s: dict) -> float:
        d = s["design"]
        b, _, k = d["body_material"].partition("*")
        out = abs(math.log(float(k or 1.0) / scale)) * 3
        for name, v in geometry.items():
            out += abs(d[name] - v) / v
        return out if (b, d["membrane_material"]) == (body, membrane) else math.inf

    best = min(_summaries(), key=distance)
    assert distance(best) < 0.08, (body, membrane, scale, geometry, best["design"])
    return _load(best["key"])


@dataclass(frozen=True)
class Truth:
    """What acts on the data besides the FE curve of the record."""

    membrane_from_record: bool = False   # read the record as membrane x 1/k, body preset
    p0_pa: float = 0.0
    k_pressure: float = 1.0
    R_pa_per_ul_s: float = 0.0
    offset_deg: float = 0.0
    k_angle: float = 1.0
    g_retarded: float = 0.0
    tau_s: float = 3.0
    compliance_ul_per_pa: float = 0.0    # air in the line (line_compliance)
    relax_g: float = 0.0                 # the pressure relaxing at a held volume: a
    relax_tau_s: float = 3.0             # standard linear solid (pressure_relaxation)
    drift_pa_per_s: float = 0.0          # the gauge's zero running away (gauge_drift)
    leak_per_s: float = 0.0              # outside: volume lost per s per (p / p_peak) x V
                                         # during holds only
    leak_ul_s_per_kpa: float = 0.0       # a leak all along: G p_chamber (chamber_leak)
    friction_deg: float = 0.0            # outside: unloading reads higher by this (bump)
    contact_deg: float = 0.0             # outside: theta_c tanh(theta / theta_c)


@dataclass(frozen=True)
class Protocol:
    flows_ul_s: tuple[float, ...] = (2.0,)   # the first sets read_s; others x2, x0.5 ...
    peak_angle_deg: float = 60.0
    hold_s: float = 0.0                      # 0: no hold
    unload: bool = True
    load_readings: int = 10
    specimens: int = 3
    noise_deg: float = 0.6
    specimen_sd_p: float = 0.03
    specimen_sd_a: float = 0.02
    seed: int = 7
    past_range: float = 1.0                  # > 1: load past the FE's last volume
    switch_between: bool = False             # the pump stops between two readings
    log_pump: bool = False                   # the "pump" column: its state before each
                                             # reading, as the pump's software logs it


def _extrap(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """np.interp, extended linearly past the last point (a lab keeps pumping after the
    FE stopped)."""
    y = np.interp(x, xp, fp)
    hi = x > xp[-1]
    if np.any(hi):
        slope = (fp[-1] - fp[-3]) / (xp[-1] - xp[-3])
        y[hi] = fp[-1] + slope * (x[hi] - xp[-1])
    return y


def _curve(rec: Record, truth: Truth) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    v, p, a = rec.volume_ul, rec.pressure_pa, rec.angle_deg
    keep = np.concatenate([[True], np.diff(v) > 0])
    v, p, a = v[keep], p[keep], a[keep]
    if truth.membrane_from_record:
        p = p / rec.scale
    return v, p, a


def _history(proto: Protocol, q: float, v_peak: float, read_s: float):
    """Fine time grid, the pump's volume and direction on it, and the reading times. The
    pump's program switches at readings (its durations are whole reading intervals)
    unless ``proto.switch_between`` (then loading ends mid-interval)."""
    t_load = max(round(v_peak / q / read_s), 2) * read_s
    if proto.switch_between:
        t_load -= 0.4 * read_s
    segs = [("load", t_load)]
    if proto.hold_s:
        segs.append(("hold", max(round(proto.hold_s / read_s), 1) * read_s))
    if proto.unload:
        segs.append(("unload", t_load))
    t_end = sum(d for _, d in segs)
    dt = min(read_s, 1.0) / 100
    t = np.arange(0.0, t_end + dt / 2, dt)
    v, d = np.zeros_like(t), np.zeros_like(t)
    t0 = v0 = 0.0
    for kind, dur in segs:
        m = (t > t0 + 1e-12) & (t <= t0 + dur + 1e-9)
        rate = {"load": q, "hold": 0.0, "unload": -q}[kind]
        v[m] = v0 + rate * (t[m] - t0)
        d[m] = np.sign(rate)
        t0, v0 = t0 + dur, v0 + rate * dur
    reads = np.arange(read_s, t_end + 1e-9, read_s)
    return t, np.maximum(v, 0.0), d, reads


def lab_rows(designs: list[tuple[Record, dict]], truth: Truth = Truth(),
             proto: Protocol = Protocol(), pump: dict | None = None) -> list[dict]:
    """Rows of the measured-data contract (docs/measured-data.md). ``designs``: each
    record with the nominal design a lab writes for it (L_mm, t_mm, T_mm, b_mm, h_mm,
    body_material, membrane_material). ``pump``, when given, gets each curve's true pump
    state before each reading (+1 in, 0 stopped, -1 out)."""
    rng = np.random.default_rng(proto.seed + SEED_OFFSET)
    rows = []
    for rec, nominal in designs:
        v_c, p_c, a_c = _curve(rec, truth)
        sign = 1.0 if a_c[-1] > 0 else -1.0
        assert sign * a_c[-1] > proto.peak_angle_deg, (rec.key, a_c[-1])  # it must bend
        v_peak = float(np.interp(proto.peak_angle_deg, sign * a_c, v_c)) * proto.past_range
        q0 = proto.flows_ul_s[0]
        read_s = max(round(v_peak / q0 / proto.load_readings / 0.05) * 0.05, 0.05)
        for q in proto.flows_ul_s:
            t, v, d, reads = _history(proto, q, v_peak, read_s)
            for s in range(proto.specimens):
                kp = 1.0 + proto.specimen_sd_p * rng.standard_normal()
                ka = 1.0 + proto.specimen_sd_a * rng.standard_normal()
                v_ch = v.copy()
                if truth.leak_per_s:
                    p_top = float(np.max(p_c))
                    lost = np.zeros_like(v)
                    for i in range(1, t.size):
                        here = max(v[i] - lost[i - 1], 0.0)
                        p_here = float(np.interp(here, v_c, p_c))
                        lost[i] = lost[i - 1] + (d[i] == 0) * truth.leak_per_s * (
                            t[i] - t[i - 1]) * here * p_here / p_top
                    v_ch = np.maximum(v - lost, 0.0)
                if truth.leak_ul_s_per_kpa:  # dV_lost/dt = G p(V - V_lost), Euler on t
                    lost = np.zeros_like(v)
                    for i in range(1, t.size):
                        here = max(v[i - 1] - lost[i - 1], 0.0)
                        p_here = kp * float(_extrap(np.array([here]), v_c, p_c)[0])
                        lost[i] = lost[i - 1] + (t[i] - t[i - 1]) * (
                            truth.leak_ul_s_per_kpa * 1e-3 * max(p_here, 0.0))
                    v_ch = np.maximum(v - lost, 0.0)
                if truth.compliance_ul_per_pa:  # V_pump = V_ch + C p(V_ch)
                    g = v_c + truth.compliance_ul_per_pa * kp * p_c
                    v_ch = np.interp(v_ch, g, v_c)
                p_ch = kp * _extrap(v_ch, v_c, p_c)
                if truth.relax_g:    # relaxed p_ch; at once (1 + g) stiffer, Euler on t
                    y = np.empty_like(p_ch)
                    y[0] = p_ch[0]
                    for i in range(1, t.size):
                        dt = t[i] - t[i - 1]
                        y[i] = y[i - 1] + dt * (p_ch[i - 1] - y[i - 1]) / truth.relax_tau_s
                    p_ch = (1 + truth.relax_g) * p_ch - truth.relax_g * y
                static = ka * _extrap(v_ch, v_c, a_c)
                if truth.contact_deg:
                    static = truth.contact_deg * np.tanh(static / truth.contact_deg)
                angle = static
                if truth.g_retarded:
                    y = np.empty_like(static)
                    y[0] = static[0]
                    for i in range(1, t.size):
                        e = math.exp(-(t[i] - t[i - 1]) / truth.tau_s)
                        y[i] = static[i] + (y[i - 1] - static[i]) * e
                    angle = (1 - truth.g_retarded) * static + truth.g_retarded * y
                if truth.friction_deg:
                    x = np.clip(np.abs(static) / max(np.max(np.abs(static)), 1e-9), 0, 1)
                    angle = angle + sign * (d < 0) * truth.friction_deg * 4 * x * (1 - x)
                gauge = (truth.k_pressure * (p_ch + truth.R_pa_per_ul_s * q * d) + truth.p0_pa
                         + truth.drift_pa_per_s * t)
                read = truth.k_angle * angle + truth.offset_deg
                idx = np.clip(np.searchsorted(t, reads - 1e-9), 0, t.size - 1)
                cid = (f"{nominal['body_material'][:4]}-L{nominal['L_mm']:g}"
                       f"-t{nominal['t_mm']:g}-q{q:g}-{s + 1}")
                if pump is not None:
                    pump[cid] = d[idx].astype(int).tolist()
                for k, i in enumerate(idx):
                    rows.append({
                        "curve_id": cid, **nominal,
                        "pressure_pa": round(float(gauge[i] + PRESSURE_NOISE_PA
                                                   * rng.standard_normal())),
                        "angle_deg": round(float(read[i] + proto.noise_deg
                                                 * rng.standard_normal()), 1),
                        "time_s": round(float(reads[k]), 2), "flow_ul_s": q,
                        **({"pump": ("unload", "hold", "load")[int(d[i]) + 1]}
                           if proto.log_pump else {})})
    return rows


def nominal(rec: Record, body: str | None = None, membrane: str | None = None) -> dict:
    """The design as a lab writes it: the record's geometry to 0.01 mm, preset materials."""
    d = rec.design
    return {"L_mm": round(d["L_mm"], 2), "t_mm": round(d["t_mm"], 2),
            "T_mm": round(d["T_mm"], 2), "b_mm": round(d["b_mm"], 2),
            "h_mm": round(d["h_mm"], 3), "body_material": body or rec.body,
            "membrane_material": membrane or rec.membrane}


# ---- the data sets ---------------------------------------------------------------------

def _std(pair: tuple[str, str], Lt: tuple[tuple[float, float], ...]) -> list:
    out = []
    for L, t in Lt:
        r = record(*pair, 1.0, L_mm=L, t_mm=t, T_mm=1.0, b_mm=1.8, h_mm=0.15)
        out.append((r, nominal(r)))
    return out


def _odd(pair: tuple[str, str], geometries: tuple[tuple[float, ...], ...]) -> list:
    """Non-standard geometries (L, t, T, b, h) whose record's body is the preset (scale
    within 2 %)."""
    out = []
    for L, t, T, b, h in geometries:
        r = record(*pair, 1.0, L_mm=L, t_mm=t, T_mm=T, b_mm=b, h_mm=h)
        out.append((r, nominal(r)))
    return out


PDMS10 = ("pdms_1_10", "ecoflex_00_30")
PDMS15 = ("pdms_1_15", "ecoflex_00_30")
REV = ("ecoflex_00_30", "pdms_1_15")
ECO = ("ecoflex_00_30", "ecoflex_00_30")


def designs_std10() -> list:
    return _std(PDMS10, ((4.1, 0.75), (15.1, 0.5), (7.1, 1.0)))


def designs_std15() -> list:
    return _std(PDMS15, ((7.1, 0.75), (17.1, 0.5), (4.1, 0.5)))


def designs_rev() -> list:
    return _std(REV, ((4.1, 0.5), (7.1, 0.75), (17.1, 1.0)))


def designs_odd_rev() -> list:
    return _odd(REV, ((17.86, 0.53, 1.645, 2.342, 0.1646), (16.38, 0.513, 0.917, 1.585, 0.198),
                      (10.37, 0.94, 0.988, 2.362, 0.1045)))


def designs_odd_eco() -> list:
    # (the ecoflex/ecoflex records at L 4.2 and 10.4 mm balloon rather than bend: 1-13 deg)
    return _odd(ECO, ((17.86, 0.53, 1.645, 2.342, 0.1646), (16.38, 0.513, 0.917, 1.585, 0.198)))


def scaled_body(k: float, L: float) -> list:
    """One PDMS 1:15 body k x its preset at an odd geometry (the lab says pdms_1_15)."""
    r = record(*PDMS15, k, L_mm=L)
    return [(r, nominal(r))]


@dataclass(frozen=True)
class Expect:
    """A right answer: ``select`` (that set, or named among the indistinguishable with
    its sizes right), ``nothing`` (and nothing flagged), ``flag`` (nothing selected, the
    residual flagged), ``none_selected`` (nothing selected, flagged or not), ``error`` (a
    one-line input error naming this column), plus warnings naming these columns."""

    kind: str
    effect: str = ""
    sizes: dict = field(default_factory=dict)
    column: str = ""
    warn: tuple[str, ...] = ()


@dataclass(frozen=True)
class Case:
    id: str
    rows: Callable[[], list[dict]]
    expect: Expect
    cheap: bool = False


def _drop(rows: list[dict], *cols: str) -> list[dict]:
    return [{k: v for k, v in r.items() if k not in cols} for r in rows]


def _first_specimen(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r["curve_id"].endswith("-1")]


# in the default suite (each failed before the loop read the bend, voted across
# replicates, said radians and headers plainly or weighed the readings by the specimens'
# scatter; 4-16 s each on the 2-core VM, 2026-12-06); the rest are marked slow, among
# them "inlet-R-80-2flows" and "friction-loop" since 2026-12-06 (28 and 23 s: the default
# suite over its 10 minutes; the inlet resistance at two flow rates and a loop outside the
# catalogue stay in tests/test_calibration_loop.py's default cases)
# "flipped-angles" slow since 2026-12-07 (the default suite 624 s; "radian-angles" keeps
# the angle column's warning in the default suite)
CHEAP = {"clean-one-design-2-flows", "clean-past-fe-range", "radian-angles",
         "unit-in-header", "unknown-unit-in-header", "membrane-0.61-L15.8", "offset-no-time",
         # air in the line, the catalogue's line_compliance (7 s, 2026-12-06); clean data
         # on which a pair with it fitted the gauge's misfit of bodies 1-2 % off the
         # preset until a pair had to beat its members in each channel (4 s)
         "compliance-bubble", "clean-reversed-odd-loop",
         # the pressure relaxing at a held volume, pressure_relaxation (9 s, 2026-12-06)
         "relaxation-0.3-rev-one-flow"}
LOOP = Protocol(hold_s=4.0)
LOOP2 = Protocol(hold_s=4.0, flows_ul_s=(1.5, 3.0))
LOADING = Protocol(unload=False)


def _cases() -> list[Case]:
    c: list[Case] = []
    nothing, flag = Expect("nothing"), Expect("flag")

    def add(cid, rows, expect):
        c.append(Case(cid, rows, expect, cid in CHEAP))

    # clean data: nothing to select
    add("clean-pdms10-std-loop", lambda: lab_rows(designs_std10(), proto=LOOP), nothing)
    add("clean-pdms15-std-loading", lambda: lab_rows(designs_std15(), proto=LOADING), nothing)
    add("clean-reversed-std-loop2", lambda: lab_rows(designs_rev(), proto=LOOP2), nothing)
    add("clean-reversed-odd-loop", lambda: lab_rows(designs_odd_rev(), proto=LOOP), nothing)
    add("clean-eco-odd-loop", lambda: lab_rows(designs_odd_eco(), proto=LOOP), nothing)
    add("clean-pdms10-no-time", lambda: _drop(lab_rows(designs_std10(), proto=LOOP),
                                              "time_s", "flow_ul_s"), nothing)
    add("clean-pdms15-no-time-loading", lambda: _drop(lab_rows(designs_std15(),
                                                               proto=LOADING),
                                                      "time_s", "flow_ul_s"), nothing)
    add("clean-2-specimens", lambda: lab_rows(designs_std10(),
                                              proto=replace(LOOP, specimens=2)), nothing)
    add("clean-4-specimens-noisy", lambda: lab_rows(designs_std15(), proto=replace(
        LOOP, specimens=4, noise_deg=0.9, seed=3)), nothing)
    add("clean-single-specimen", lambda: _first_specimen(lab_rows(designs_std10(),
                                                                  proto=LOOP)), nothing)
    # three curves of one specimen each: a pair of effects fitted its folds' two curves'
    # own deviations and "predicted" the third (loop._judge, MIN_SPARE_CURVES)
    add("clean-single-specimen-seed-107", lambda: _first_specimen(
        lab_rows(designs_std10(), proto=replace(LOOP, seed=107))), nothing)
    add("clean-one-design-2-flows", lambda: lab_rows(designs_odd_eco()[:1], proto=LOOP2),
        nothing)
    add("clean-pump-stops-between-readings", lambda: lab_rows(designs_std15(), proto=replace(
        LOOP, switch_between=True)), nothing)
    add("clean-past-fe-range", lambda: lab_rows(designs_std15(), proto=replace(
        LOOP, peak_angle_deg=85.0, past_range=1.3)),
        Expect("nothing", warn=("time_s",)))
    add("clean-duplicated-rows", lambda: (lambda r: r + r)(lab_rows(designs_std10(),
                                                                    proto=LOOP)),
        Expect("nothing", warn=("rows",)))
    add("clean-duplicated-no-time", lambda: (lambda r: r + r)(_drop(
        lab_rows(designs_std10(), proto=LOOP), "time_s", "flow_ul_s")),
        Expect("nothing", warn=("rows",)))
    add("kpa-pressures", lambda: [dict(r, pressure_pa=r["pressure_pa"] / 1000) for r in
                                  lab_rows(designs_std10(), proto=LOOP)],
        Expect("none_selected", warn=("pressure_pa",)))
    add("radian-angles", lambda: [dict(r, angle_deg=round(math.radians(r["angle_deg"]), 4))
                                  for r in lab_rows(designs_std10(), proto=LOOP)],
        Expect("none_selected", warn=("angle_deg",)))
    # a protocol that counts the bend positive towards the membrane (2026-12-06)
    add("flipped-angles", lambda: [dict(r, angle_deg=-r["angle_deg"]) for r in
                                   lab_rows(designs_std10(), proto=LOOP)],
        Expect("none_selected", warn=("angle_deg",)))
    # a header with its unit is read and converted (docs/measured-data.md, "Headers with
    # units"; an error naming the column until 2026-12-06): clean data, nothing to select
    add("unit-in-header", lambda: [{("Pressure (kPa)" if k == "pressure_pa" else k):
                                    (v / 1000.0 if k == "pressure_pa" else v)
                                    for k, v in r.items()}
                                   for r in lab_rows(designs_std10()[:1], proto=LOOP)],
        Expect("nothing"))
    add("unknown-unit-in-header", lambda: [{("Pressure (atm?)" if k == "pressure_pa" else k): v
                                            for k, v in r.items()}
                                           for r in lab_rows(designs_std10()[:1], proto=LOOP)],
        Expect("error", column="Pressure (atm?)", warn=("kpa",)))
    add("unit-in-values", lambda: [dict(r, pressure_pa=f"{r['pressure_pa']} Pa") for r in
                                   lab_rows(designs_std10()[:1], proto=LOOP)],
        Expect("error", column="pressure_pa"))
    add("one-curve", lambda: _first_specimen(lab_rows(designs_std10()[:1], proto=LOADING)),
        Expect("error", column="curve_id"))
    # measurement effects, on designs other than the test cases'
    add("pressure-offset-150", lambda: lab_rows(designs_std15(), Truth(p0_pa=150.0), LOADING),
        Expect("select", "pressure_offset", {"p0_pa": 150.0}))
    add("pressure-offset-rev", lambda: lab_rows(designs_rev(), Truth(p0_pa=-120.0), LOOP),
        Expect("select", "pressure_offset", {"p0_pa": -120.0}))
    add("pressure-gain-0.93", lambda: lab_rows(designs_std10(), Truth(k_pressure=0.93), LOOP),
        Expect("select", "pressure_gain", {"k_pressure": 0.93}))
    add("inlet-R-80-2flows", lambda: lab_rows(designs_std15(), Truth(R_pa_per_ul_s=80.0),
                                              LOOP2),
        Expect("select", "hydraulic_resistance", {"R_pa_per_ul_s": 80.0}))
    add("inlet-R-50-odd", lambda: lab_rows(designs_odd_eco(), Truth(R_pa_per_ul_s=50.0), LOOP),
        Expect("select", "hydraulic_resistance", {"R_pa_per_ul_s": 50.0}))
    add("angle-offset-minus3", lambda: lab_rows(designs_std10(), Truth(offset_deg=-3.0),
                                                LOOP),
        Expect("select", "angle_offset", {"offset_deg": -3.0}))
    add("angle-offset-rev", lambda: lab_rows(designs_rev(), Truth(offset_deg=2.5), LOADING),
        Expect("select", "angle_offset", {"offset_deg": 2.5}))
    add("camera-gain-0.9", lambda: lab_rows(designs_std10(), Truth(k_angle=0.9), LOOP),
        Expect("select", "camera_gain", {"k_angle": 0.9}))
    add("camera-gain-rev-1.1", lambda: lab_rows(designs_rev(), Truth(k_angle=1.1), LOOP),
        Expect("select", "camera_gain", {"k_angle": 1.1}))
    add("creep-0.2-hold", lambda: lab_rows(designs_std15(), Truth(g_retarded=0.2, tau_s=3.0),
                                           LOOP2),
        Expect("select", "viscoelastic_creep", {"g_retarded": 0.2, "tau_retardation_s": 3.0}))
    add("creep-0.3-odd-one-flow", lambda: lab_rows(designs_odd_eco(),
                                                   Truth(g_retarded=0.3, tau_s=2.0), LOOP),
        Expect("select", "viscoelastic_creep", {"g_retarded": 0.3, "tau_retardation_s": 2.0}))
    add("offset-no-time", lambda: _drop(lab_rows(designs_std10(), Truth(offset_deg=2.5),
                                                 LOOP), "time_s", "flow_ul_s"),
        Expect("select", "angle_offset", {"offset_deg": 2.5}))
    add("creep-no-time", lambda: _drop(lab_rows(designs_std15(), Truth(g_retarded=0.3), LOOP),
                                       "time_s", "flow_ul_s"), Expect("none_selected"))
    # physical effects through the FE: a stiffer body, a softer membrane
    add("body-1.65-L11.4", lambda: lab_rows(scaled_body(1.64719, 11.37), proto=LOOP2),
        Expect("select", "body_stiffness", {"body_mu_scale": 1.64719}))
    add("body-1.34-L6.4", lambda: lab_rows(scaled_body(1.34418, 6.406), proto=LOOP2),
        Expect("select", "body_stiffness", {"body_mu_scale": 1.34418}))
    add("membrane-0.74-L6.4", lambda: lab_rows(scaled_body(1.34418, 6.406),
                                               Truth(membrane_from_record=True), LOOP2),
        Expect("select", "membrane_stiffness", {"membrane_mu_scale": 1 / 1.34418}))
    add("membrane-0.61-L15.8", lambda: lab_rows(scaled_body(1.63645, 15.79),
                                                Truth(membrane_from_record=True), LOOP2),
        Expect("select", "membrane_stiffness", {"membrane_mu_scale": 1 / 1.63645}))
    # the pressure relaxing at a held volume (pressure_relaxation, 2026-12-06)
    add("relaxation-0.2-hold", lambda: lab_rows(designs_std15(),
                                                Truth(relax_g=0.2, relax_tau_s=3.0), LOOP2),
        Expect("select", "pressure_relaxation", {"g_relaxing": 0.2,
                                                 "tau_relaxation_s": 3.0}))
    add("relaxation-0.3-rev-one-flow", lambda: lab_rows(
        designs_rev(), Truth(relax_g=0.3, relax_tau_s=2.0), LOOP),
        Expect("select", "pressure_relaxation", {"g_relaxing": 0.3,
                                                 "tau_relaxation_s": 2.0}))
    # a leak all along (chamber_leak, 2026-12-06)
    add("leak-0.2-hold", lambda: lab_rows(designs_std15(), Truth(leak_ul_s_per_kpa=0.2),
                                          replace(LOOP, hold_s=6.0)),
        Expect("select", "chamber_leak", {"G_ul_s_per_kpa": 0.2}))
    add("leak-0.3-odd-eco-2flows", lambda: lab_rows(designs_odd_eco(),
                                                    Truth(leak_ul_s_per_kpa=0.3), LOOP2),
        Expect("select", "chamber_leak", {"G_ul_s_per_kpa": 0.3}))
    # a leak so fast that its holds read as unloading, unless the pump's log is given
    add("leak-0.5-hold-pump-log", lambda: lab_rows(
        designs_std15(), Truth(leak_ul_s_per_kpa=0.5), replace(LOOP, hold_s=6.0,
                                                               log_pump=True)),
        Expect("select", "chamber_leak", {"G_ul_s_per_kpa": 0.5}))
    # the gauge's zero drifting during each run (gauge_drift, 2026-12-06)
    add("gauge-drift-4", lambda: lab_rows(designs_std10(), Truth(drift_pa_per_s=4.0), LOOP),
        Expect("select", "gauge_drift", {"drift_pa_per_s": 4.0}))
    add("gauge-drift-minus3-rev-2flows", lambda: lab_rows(
        designs_rev(), Truth(drift_pa_per_s=-3.0), LOOP2),
        Expect("select", "gauge_drift", {"drift_pa_per_s": -3.0}))
    # air in the line: since 2026-12-06 in the catalogue (line_compliance)
    add("compliance-bubble", lambda: lab_rows(designs_std10(),
                                              Truth(compliance_ul_per_pa=0.004), LOOP),
        Expect("select", "line_compliance", {"C_ul_per_kpa": 4.0}))
    # outside the catalogue
    add("leak-during-hold", lambda: lab_rows(designs_std15(), Truth(leak_per_s=0.08),
                                             replace(LOOP, hold_s=6.0)), flag)
    add("friction-loop", lambda: lab_rows(designs_std10(), Truth(friction_deg=4.0), LOOP),
        flag)
    add("contact-rev", lambda: lab_rows(designs_rev(), Truth(contact_deg=30.0),
                                        replace(LOOP, peak_angle_deg=75.0)), flag)
    return c


CASES = _cases()


def judge(case: Case, report: dict | None, error: BaseException | None) -> tuple[bool, str]:
    """Whether the answer is right, and what it was (one line)."""
    from solver.errors import InputError

    e = case.expect
    if error is not None:
        if not isinstance(error, InputError):
            return False, f"traceback: {type(error).__name__}: {error}"
        text = str(error)
        if e.kind != "error":
            return False, f"refused: {text}"
        ok = (getattr(error, "field", None) == e.column and "\n" not in text
              and all(w in text for w in e.warn))  # an error names what it found
        return ok, f"error on {getattr(error, 'field', None)}: {text[:90]}"
    assert report is not None
    sel = report["selected_effects"]
    flagged = report["residual_structured_after"]
    left = f" (flagged {report['unexplained_rms_deg']:.2f})" if flagged else ""
    what = (f"{'+'.join(sel) or 'nothing'}{left}"
            f"; {report['rmse_before_deg']:.2f} -> {report['rmse_after_deg']:.2f}"
            f" (floor {report['noise_floor_deg'] or float('nan'):.2f})")
    if report["rmse_after_deg"] > report["rmse_before_deg"] + 1e-12:
        return False, "rmse_after above rmse_before: " + what
    for col in e.warn:
        if not any(w.startswith(col) for w in report["warnings"]):
            return False, f"no warning on {col}: " + what
    if e.kind == "error":
        return False, "accepted: " + what
    if e.kind == "nothing":
        return (not sel and not flagged), what
    if e.kind == "flag":
        return (not sel and flagged), what
    if e.kind == "none_selected":
        return not sel, what
    # select
    truth = e.sizes
    fitted = report["fitted"]["effects"]
    if sel == [e.effect]:
        ok = all(abs(fitted[n]["value"] - v) <= 3 * fitted[n]["sd"] + 1e-12
                 for n, v in truth.items())
        sizes = ", ".join(f"{n} {fitted[n]['value']:.3g}+/-{fitted[n]['sd']:.2g} ({v:g})"
                          for n, v in truth.items())
        return ok, what + "; " + sizes
    alike = {tuple(a["effects"]): a for a in report["indistinguishable"]}
    if (e.effect,) in alike:
        p = alike[(e.effect,)]["params"]
        ok = all(abs(p[n]["value"] - v) <= 3 * p[n]["sd"] for n, v in truth.items())
        return ok, what + f"; {e.effect} named indistinguishable"
    return False, what


def run_case(case: Case):
    """(report or None, error or None, rows). A case of ``CASES`` is calibrated once per
    process at a seed offset and baseline (``calibrated``): its report is a copy each time."""
    if any(c is case for c in CASES):
        cal, error, rows = calibrated(case.id, SEED_OFFSET, _emulator)
    else:
        cal, error, rows = _calibrate(case)
    return (None if cal is None else copy.deepcopy(cal.report)), error, rows


def _calibrate(case: Case):
    """(calibration or None, error or None, rows)."""
    from surrogate.calibration import run_calibration

    rows = case.rows()
    try:
        return run_calibration(rows, _emulator()), None, rows
    except Exception as exc:  # an InputError is judged; any other is a traceback
        return None, exc, rows


@functools.lru_cache(maxsize=16)
def calibrated(case_id: str, seed_offset: int, baseline: Callable):
    """``_calibrate`` of the case ``case_id`` of ``CASES`` at ``seed_offset`` (the module's
    SEED_OFFSET when called) against ``baseline()``, kept: the cheap cases are read by
    tests/test_calibration_statistics.py and test_calibration_saved_design.py too (one
    calibration each, 3-6 s, where there were two)."""
    return _calibrate(next(c for c in CASES if c.id == case_id))


@functools.cache
def _emulator():
    from surrogate.emulator.file import load_emulator

    return load_emulator(Path(__file__).resolve().parents[1] / "service" / "data"
                         / "emulator.json")


@pytest.mark.parametrize("designs, truth, proto", [
    (designs_std10, Truth(), LOOP),                      # top of stiff curves: flat gauge
    (designs_std15, Truth(g_retarded=0.3, tau_s=2.0), LOOP2),   # creep during the hold
    (designs_odd_eco, Truth(R_pa_per_ul_s=50.0), LOOP),  # one hold reading after R Q's step
    (designs_std10, Truth(friction_deg=4.0), LOOP),      # a loop: unloading bends less
    (designs_std10, Truth(offset_deg=-3.0), LOOP),       # the bend crosses zero
    (designs_rev, Truth(), replace(LOOP, specimens=4, noise_deg=0.9, seed=3)),
], ids=["stiff-top", "creep-hold", "inlet-step", "friction", "offset", "reversed-noisy"])
def test_loading_holds_and_unloading_are_read_as_the_pump_ran(designs, truth, proto):
    # the noise floor compares replicates segment by segment and the injected volume
    # follows the pump's state: one misread reading shifts every later volume
    from surrogate.calibration import observations_from_rows

    pump: dict[str, list[int]] = {}
    obs = observations_from_rows(lab_rows(designs(), truth, proto, pump))
    wrong = [(obs.curve_ids[c], "".join("+0-"[1 - int(x)] for x in obs.direction[obs.curve == c]),
              "".join("+0-"[1 - x] for x in pump[obs.curve_ids[c]]))
             for c in range(obs.n_curves)
             if obs.direction[obs.curve == c].tolist() != pump[obs.curve_ids[c]]]
    assert not wrong, wrong


# measured 2026-12-03 (2155-record emulator, seed 7): what the loop still gets wrong (the
# inlet resistance at the Ecoflex designs and the camera offset without time_s are right
# since the baseline's pressure scale and the specimens' scatter are counted: _backing.py,
# _specimens.py)
WRONG: dict[str, str] = {
    "creep-0.3-odd-one-flow": (
        "measured 2026-12-04 on the emulator whose pressure nodes share one kernel: 30 % creep "
        "at one flow rate on the odd Ecoflex designs reads g 0.194 +/- 0.035 for 0.3, 3.03 sd "
        "off; the emulator before it read the same 0.194 +/- 0.035 and passed by 0.3 % of an "
        "sd: at one flow rate the creep trades with the pump's switch times")}
# (before the switch times were freed whenever they help, 2026-12-04, this set read g 0.17:
# the creep absorbed the switches' misfit)


@pytest.mark.parametrize("case", [
    pytest.param(c, marks=([] if c.cheap else [pytest.mark.slow])
                 + ([pytest.mark.xfail(reason=WRONG[c.id], strict=False)]
                    if c.id in WRONG else []))
    for c in CASES], ids=[c.id for c in CASES])
def test_unseen_lab_data(case):
    report, error, _ = run_case(case)
    ok, what = judge(case, report, error)
    assert ok, what


def test_clean_data_on_designs_written_to_0_01_mm_select_no_physical_change(monkeypatch):
    """Clean FE data of two Ecoflex/Ecoflex records whose dimensions the lab wrote to 0.01
    mm (T 1.6453 -> 1.65, b 2.3416 -> 2.34): the emulator, exact at the records' own
    dimensions to 0.02 deg, differs at the written ones by up to 1.3 deg. With the noise
    of seed offset 100 a stiffer body of 0.988 +/- 0.003 was selected for that rounding;
    the nominal dimensions' resolution in the baseline's uncertainty (_backing.py) makes
    it 0.988 +/- 0.012 (shipped emulator), not significant."""
    monkeypatch.setattr(sys.modules[__name__], "SEED_OFFSET", 100)
    case = next(c for c in CASES if c.id == "clean-eco-odd-loop")
    report, error, _ = run_case(case)
    assert error is None and report["selected_effects"] == [], judge(case, report, error)[1]


def test_a_pump_stopping_between_readings_is_found_and_timed():
    """Clean FE data whose pump program stops 0.4 of a reading interval before a reading
    and restarts (unloading) 0.4 before another. Before the loop fitted the switch times
    (the injected volume put every change at a reading) it flagged 3.1 deg on these clean
    data as an effect outside the catalogue. Now it frees them, says so, and recovers the
    shift: -0.4 where the data put the change at the reading after it, +0.6 where the
    pressure's step put it at the reading before."""
    case = next(c for c in CASES if c.id == "clean-pump-stops-between-readings")
    report, error, _ = run_case(case)
    assert error is None and report["selected_effects"] == []
    pump = report["pump_switches"]
    assert pump["open"] and pump["rmse_cv_with_deg"] < 0.5 * pump["rmse_cv_without_deg"]
    assert "between readings" in report["interpretation"]
    sure = [s for s in pump["shifts"] if s["sd"] < 0.1]
    assert len(sure) >= 3
    for s in sure:
        x = s["shift_reading_intervals"]
        assert min(abs(x + 0.4), abs(x - 0.6)) < max(3 * s["sd"], 0.12), s


@pytest.mark.parametrize("seed_offset", [400, 402, 410, 427])
def test_creep_without_time_is_not_explained_by_an_offset(monkeypatch, seed_offset):
    """PDMS 1:15 curves with creep (g 0.3), loaded, held and unloaded, without time_s:
    no catalogued effect can carry creep without time, yet at these noise seeds an angle
    offset (with a camera gain at 402 and 410) was selected. Its residuals run along
    every curve (lag-1 z 13.7-14.0, runs z -12.7 to -11.9 beyond each specimen's own
    scale; clean sets within +-2.6), but the replicates share them at S^2 / se 2.2-2.9
    only: read against the gauge pressure the within-curve test counts too."""
    monkeypatch.setattr(sys.modules[__name__], "SEED_OFFSET", seed_offset)
    case = next(c for c in CASES if c.id == "creep-no-time")
    report, error, _ = run_case(case)
    ok, what = judge(case, report, error)
    assert ok, what
    assert report["selected_effects"] == []


def regulator_rows(designs: list, truth: Truth = Truth(), seed: int = 0,
                   step_pa: float = 250.0, specimens: int = 3) -> list[dict]:
    """A lab with a pressure regulator: set points every ``step_pa`` up to the pressure of
    60 deg and back down, one steady reading each; no pump, no time_s. Each specimen's
    stiffness scatters by 3 % (its pressure scale) and its angle by 2 %; the gauge reads
    the set point with 3 Pa noise, the camera 0.6 deg."""
    rng = np.random.default_rng(seed)
    rows = []
    for rec, nominal in designs:
        _, p, a = _curve(rec, truth)
        sign = 1.0 if a[-1] > 0 else -1.0
        sets = np.arange(step_pa, float(np.interp(60.0, sign * a, p)) + 1e-9, step_pa)
        sets = np.concatenate([sets, sets[-2::-1]])
        for s in range(specimens):
            sp, sa = 1.0 + 0.03 * rng.standard_normal(), 1.0 + 0.02 * rng.standard_normal()
            for gauge in sets:
                chamber = (gauge - truth.p0_pa) / truth.k_pressure
                angle = sa * np.interp(chamber / sp, p, a)
                rows.append({"curve_id": f"{rec.key[:18]}-s{s + 1}", **nominal,
                             "pressure_pa": round(float(gauge + 3 * rng.standard_normal()), 1),
                             "angle_deg": round(float(truth.k_angle * angle + truth.offset_deg
                                                      + 0.6 * rng.standard_normal()), 2)})
    return rows


@pytest.mark.parametrize("truth, expect", [
    (Truth(), Expect("nothing")),
    (Truth(offset_deg=2.5), Expect("select", "angle_offset", {"offset_deg": 2.5})),
    (Truth(k_angle=0.9), Expect("select", "camera_gain", {"k_angle": 0.9}))],
    ids=["clean", "offset", "camera-gain"])
def test_a_regulator_lab_whose_three_specimens_happen_to_agree(truth, expect):
    """PDMS 1:10 at the paper's designs, read at regulator set points (no time_s), noise
    seed 0: the three specimens of each design happen to agree, so the floor (1.13 deg)
    and the spread-based errors of the floor and the cross-validated error are all small.
    The clean set was flagged at 1.64x its floor as an effect outside the catalogue, and
    the same specimens kept the offset and the gain from being selected. The allowance
    now counts the specimens it rests on (_residual.specimen_units: at least 1.75x with 6
    and 9 degrees of freedom)."""
    case = Case("regulator", lambda: regulator_rows(designs_std10(), truth, seed=0), expect)
    report, error, _ = run_case(case)
    ok, what = judge(case, report, error)
    assert ok, what
