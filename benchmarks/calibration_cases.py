"""The calibration loop's test cases as a table, and the emulator's own error at the FE
solves they are made from (docs/calibration.md, "Tests").

    .venv/bin/python benchmarks/calibration_cases.py                 # every case
    .venv/bin/python benchmarks/calibration_cases.py camera_gain     # some cases
    .venv/bin/python benchmarks/calibration_cases.py --emulator-error
    .venv/bin/python benchmarks/calibration_cases.py --emulator PATH --reports DIR
    .venv/bin/python benchmarks/calibration_cases.py --unseen [CASE ...]
    .venv/bin/python benchmarks/calibration_cases.py --unseen --seed-offset 100   # other noise
    .venv/bin/python benchmarks/calibration_cases.py --unseen creep-no-time \
        --seed-offset 400 --seeds 30                         # a rate over 30 noise seeds
    .venv/bin/python benchmarks/calibration_cases.py --regulator 10   # a regulator lab
    .venv/bin/python benchmarks/calibration_cases.py --near-fe-end 2  # pumped to 85 deg

The cases are those of tests/test_calibration_loop.py (same labs, truths and seed), run
against the shipped emulator (or ``--emulator PATH``); one markdown row per case:
selected set, recovered size +- sd (truth), CV error before -> after, noise floor, their
ratio, and what else the report says (explanations the data cannot tell apart, ``*``: not
backed by the emulator; a better fit it cannot back; structure left). ``--emulator-error``
compares the emulator with every cached FE curve (to 60 deg): RMS error against the RMS of
its band's sd (band / 1.96) -- what the band claims against what it is. ``--unseen``
runs the data sets of tests/test_calibration_unseen.py (database records, another lab's
protocol, lab mishaps) against the shipped emulator: right or not per set, what the
report says, CPU seconds, and the count.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import calibration_lab as lab_mod  # noqa: E402
import test_calibration_loop as cases_mod  # noqa: E402
from calibration_lab import FULL_LOOP, Lab, Truth, fe, measure  # noqa: E402

from solver.errors import InputError  # noqa: E402
from surrogate.calibration import run_calibration  # noqa: E402

ANGLE_MAX_DEG = 60.0


def cases() -> list[tuple[str, Lab, Truth, dict[str, float]]]:
    """(id, lab, truth, true sizes) of every loop test case."""
    bases, paper = cases_mod.BASES, cases_mod.PAPER_DESIGNS
    out = [("clean-3", Lab(designs=bases, protocol=FULL_LOOP), Truth(), {}),
           ("clean-6", Lab(designs=paper, protocol=FULL_LOOP), Truth(), {}),
           ("reversed", Lab(designs=((7.1, 0.5), (11.1, 0.5)), materials=fe.REVERSED,
                            protocol=FULL_LOOP), Truth(), {})]
    for case_id, c in zip(cases_mod.MEASUREMENT_IDS, cases_mod.MEASUREMENT_CASES,
                          strict=True):
        _, truth, values, protocol, flows = getattr(c, "values", c)
        out.append((case_id, Lab(designs=bases, protocol=protocol, flows_ul_s=flows), truth,
                    values))
        if case_id == "camera_gain":   # the strict case: where the designs tell it apart
            out.append(("camera_gain-6", Lab(designs=paper, protocol=protocol,
                                             flows_ul_s=flows), truth, values))
    for case_id, (_, truth, values, designs, _) in zip(cases_mod.PHYSICAL_IDS,
                                                       cases_mod.PHYSICAL_CASES, strict=True):
        out.append((case_id, Lab(designs=designs, protocol=FULL_LOOP), truth, values))
    out += [("hysteresis", Lab(designs=bases, protocol=FULL_LOOP), Truth(hysteresis_deg=5.0),
             {}),
            ("contact", Lab(designs=bases, protocol=FULL_LOOP), Truth(contact_deg=25.0), {})]
    return out


def row(case_id: str, report: dict, truth: dict[str, float], seconds: float) -> str:
    fitted = report["fitted"]["effects"]
    sizes = "; ".join(f"{n} {p['value']:.4g} +/- {p['sd']:.2g}" for n, p in fitted.items())
    if sizes and truth:
        sizes += " (" + ", ".join(f"{v:g}" for v in truth.values()) + ")"
    notes = []
    alike = report.get("indistinguishable") or []
    if alike:
        notes.append("alike: " + ", ".join("+".join(a["effects"]) + ("" if a["backed"]
                                                                       else "*")
                                           for a in alike))
    u = report.get("unbacked_better")
    if u:
        notes.append("unbacked better: " + "+".join(u["effects"]) + " " + "; ".join(
            f"{p['value']:.3g} +/- {p['sd']:.2g}" for p in u["params"].values()))
    if report["residual_structured_after"]:
        notes.append(f"flagged, {report['unexplained_rms_deg']:.2f} deg unexplained")
    floor = report["noise_floor_deg"]
    return (f"| {case_id} | {', '.join(report['selected_effects']) or 'nothing'} | "
            f"{sizes or '-'} | {report['rmse_before_deg']:.2f} -> "
            f"{report['rmse_after_deg']:.2f} | {floor:.2f} | "
            f"{report['rmse_after_deg'] / floor:.2f} | {'; '.join(notes)} | {seconds:.0f} |")


def emulator_error(emulator) -> None:
    """The emulator against every cached FE curve: RMS error and RMS band sd (deg)."""
    print("| FE solve | readings | RMS error | mean error | RMS band sd |")
    print("|---|---|---|---|---|")
    for key, c in lab_mod.FE_CURVES.items():
        m = np.abs(c.angle_deg) <= ANGLE_MAX_DEG
        try:
            out = emulator.predict(fe.design_of(c.case), np.clip(c.pressure_pa[m], 0, None))
        except InputError as exc:  # outside the box: a row of the table
            print(f"| {key} | refused: {str(exc)[:60]} | | | |")
            continue
        a = np.asarray(out.angle_deg, float)
        ok = np.isfinite(a)
        err = a[ok] - c.angle_deg[m][ok]
        sd = 0.5 * (np.asarray(out.upper_deg) - np.asarray(out.lower_deg))[ok] / 1.959964
        print(f"| {key} | {int(ok.sum())} | {np.sqrt(np.mean(err**2)):.2f} | "
              f"{err.mean():+.2f} | {np.sqrt(np.mean(sd**2)):.2f} |")


def write_report(reports: Path | None, case_id: str, report: dict | None) -> None:
    """``report`` as ``reports/<case_id>.json`` (nothing without a directory or a report)."""
    if reports is None or report is None:
        return
    reports.mkdir(parents=True, exist_ok=True)
    (reports / f"{case_id}.json").write_text(json.dumps(
        report, default=lambda o: o.item() if hasattr(o, "item") else str(o)))


def unseen(wanted: list[str], emulator_path: Path | None = None, seed_offset: int = 0,
           reports: Path | None = None) -> int:
    """The unseen-lab data sets: one line each (right or not, what the report says, CPU
    seconds) and the count; with ``emulator_path`` that emulator as the baseline instead
    of the shipped one; ``seed_offset`` added to every protocol's noise seed; each report
    written to ``reports`` when given."""
    import test_calibration_unseen as unseen_mod

    unseen_mod.SEED_OFFSET = seed_offset

    if emulator_path is not None:
        from surrogate.emulator.file import load_emulator

        unseen_mod._emulator = lambda: load_emulator(emulator_path)

    right = n = 0
    for case in unseen_mod.CASES:
        if wanted and not any(w in case.id for w in wanted):
            continue
        t0 = time.process_time()
        report, error, _ = unseen_mod.run_case(case)
        ok, what = unseen_mod.judge(case, report, error)
        write_report(reports, case.id, report)
        n += 1
        right += ok
        print(f"{'right' if ok else 'WRONG'} | {case.id} | {what} | "
              f"{time.process_time() - t0:.1f} s", flush=True)
    print(f"right in {right} of {n}")
    return 0


def unseen_over_seeds(wanted: list[str], seed_offset: int, seeds: int) -> int:
    """Each wanted unseen set at the noise seed offsets ``seed_offset`` ...
    ``seed_offset + seeds - 1``: how often it is right, and its misses (a rate, where one
    seed says little)."""
    import test_calibration_unseen as unseen_mod

    for case in unseen_mod.CASES:
        if wanted and not any(w in case.id for w in wanted):
            continue
        right, misses = 0, []
        for k in range(seed_offset, seed_offset + seeds):
            unseen_mod.SEED_OFFSET = k
            report, error, _ = unseen_mod.run_case(case)
            ok, what = unseen_mod.judge(case, report, error)
            right += ok
            if not ok:
                misses.append(f"{k}: {what}")
        print(f"{case.id}: right at {right} of {seeds} seed offsets "
              f"({seed_offset}-{seed_offset + seeds - 1})", flush=True)
        for m in misses:
            print(f"    {m}")
    return 0


def regulator(seeds: int) -> int:
    """A lab with a pressure regulator (tests/test_calibration_unseen.regulator_rows: set
    points up to 60 deg and back, no pump, no time_s, 3 specimens): six truths at noise
    seeds 0 ... ``seeds`` - 1, one line each and the count."""
    import test_calibration_unseen as u

    truths = [
        ("clean-pdms10", u.designs_std10, u.Truth(), u.Expect("nothing")),
        ("clean-pdms15", u.designs_std15, u.Truth(), u.Expect("nothing")),
        ("clean-reversed", u.designs_rev, u.Truth(), u.Expect("nothing")),
        ("angle-offset-2.5", u.designs_std10, u.Truth(offset_deg=2.5),
         u.Expect("select", "angle_offset", {"offset_deg": 2.5})),
        ("pressure-offset-150", u.designs_std15, u.Truth(p0_pa=150.0),
         u.Expect("select", "pressure_offset", {"p0_pa": 150.0})),
        ("camera-gain-0.9", u.designs_std10, u.Truth(k_angle=0.9),
         u.Expect("select", "camera_gain", {"k_angle": 0.9})),
    ]
    right = n = 0
    for seed in range(seeds):
        for name, designs, truth, expect in truths:
            case = u.Case(f"regulator-{name}", lambda d=designs, t=truth, k=seed:
                          u.regulator_rows(d(), t, seed=k), expect)
            report, error, _ = u.run_case(case)
            ok, what = u.judge(case, report, error)
            right += ok
            n += 1
            print(f"{'right' if ok else 'WRONG'} | {seed} | {case.id} | {what}", flush=True)
    print(f"right in {right} of {n}")
    return 0


def near_fe_end(seeds: int) -> int:
    """A membrane 1.3x or 0.75x stiff, one design of tests/calibration_lab's FE solves,
    3 specimens pumped at 2.5 ul/s to ~85 deg and back, read every 2 s (tests/
    test_calibration_near_the_fe_end.py): right when membrane_stiffness alone is selected
    within 3 sd of the truth; one line per set and the count."""
    import test_calibration_near_the_fe_end as near

    right = n = 0
    for L_mm, t_mm, scale in ((7.1, 0.75, 1.3), (11.1, 0.5, 1.3), (4.1, 0.5, 1.3),
                              (7.1, 0.75, 0.75), (11.1, 0.5, 0.75)):
        for seed in range(1, seeds + 1):
            report = run_calibration(near._pumped_to_85_deg(L_mm, t_mm, scale, seed),
                                     lab_mod.emulator()).report
            fitted = report["fitted"]["effects"].get("membrane_mu_scale")
            ok = (report["selected_effects"] == ["membrane_stiffness"] and fitted is not None
                  and abs(fitted["value"] - scale) < 3.0 * fitted["sd"])
            right += ok
            n += 1
            size = ("-" if fitted is None else
                    f"{fitted['value']:.4f} +/- {fitted['sd']:.2g}")
            print(f"{'right' if ok else 'WRONG'} | L {L_mm:g} t {t_mm:g} membrane x{scale:g} | "
                  f"seed {seed} | {report['selected_effects']} {size}", flush=True)
    print(f"right in {right} of {n}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", help="case ids (default: every case)")
    parser.add_argument("--emulator", type=Path, default=lab_mod.EMULATOR_PATH)
    parser.add_argument("--emulator-error", action="store_true")
    parser.add_argument("--reports", type=Path, help="write each case's report here")
    parser.add_argument("--unseen", action="store_true",
                        help="the unseen-lab data sets (tests/test_calibration_unseen.py)")
    parser.add_argument("--seed-offset", type=int, default=0,
                        help="with --unseen: added to every protocol's noise seed")
    parser.add_argument("--seeds", type=int, default=None, metavar="N",
                        help="with --unseen and case ids: each case at N seed offsets from "
                             "--seed-offset on, counted")
    parser.add_argument("--regulator", type=int, default=None, metavar="N",
                        help="a pressure-regulator lab (no pump, no time_s): six truths at "
                             "noise seeds 0 .. N-1")
    parser.add_argument("--near-fe-end", type=int, default=None, metavar="N",
                        help="a membrane change read by a pump to ~85 deg, near the FE's "
                             "end: five designs at noise seeds 1 .. N")
    args = parser.parse_args(argv)
    if args.near_fe_end is not None:
        if args.near_fe_end < 1:
            parser.error("--near-fe-end N needs N >= 1 seeds")
        return near_fe_end(args.near_fe_end)
    if args.regulator is not None:
        if args.regulator < 1:
            parser.error("--regulator N needs N >= 1 seeds")
        return regulator(args.regulator)
    if args.seeds is not None:
        if not args.unseen or not args.cases or args.seeds < 1:
            parser.error("--seeds N (N >= 1) goes with --unseen and case ids")
        return unseen_over_seeds(args.cases, args.seed_offset, args.seeds)
    if args.unseen:
        return unseen(args.cases, args.emulator, args.seed_offset, args.reports)
    from surrogate.emulator.file import load_emulator

    emulator = load_emulator(args.emulator)
    if args.emulator_error:
        emulator_error(emulator)
        return 0
    print(f"emulator: {args.emulator} ({emulator.provenance.get('database_records')} records)")
    print("| case | selected | size (truth) | CV before -> after | floor | after / floor "
          "| also | s |")
    print("|---|---|---|---|---|---|---|---|")
    for case_id, lab, truth, values in cases():
        if args.cases and case_id not in args.cases:
            continue
        t0 = time.perf_counter()
        report = run_calibration(measure(lab, truth), emulator).report
        print(row(case_id, report, values, time.perf_counter() - t0), flush=True)
        write_report(args.reports, case_id, report)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
