"""FE curves the calibration tests make their measured data from (cached in tests/data).

The calibration must be tested on data the fitting code did not make: these are solves of
the project's own FE solver (``solver.solve``, default settings: volume control, the
default mesh, free tip, stop at 90 deg), at the paper's designs, the reversed material
pair, and designs changed the way a lab's actuators differ from nominal (membrane or body
stiffer/softer, thinner membrane, longer chamber). Each curve keeps the FE's pressure
(Pa), injected volume (ul) and angle (deg) per converged step: a lab pumping at Q ul/s
reads the curve at volume Q t.

Regenerate (one command; 23 solves of ~15-60 s each on an idle machine, 10-18 min each
on a loaded one; run one at a time):

    .venv/bin/python tests/fe_calibration_curves.py            # solve what is missing
    .venv/bin/python tests/fe_calibration_curves.py --fresh    # solve everything again

(``--fresh`` after a change of the solver's defaults: the file records the package
version, the git commit and the settings that made it.)
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

PATH = Path(__file__).parent / "data" / "fe_calibration_curves.npz"

PAPER = ("pdms_1_10", "ecoflex_00_30")
REVERSED = ("ecoflex_00_30", "pdms_1_15")


@dataclass(frozen=True)
class CaseSpec:
    """One FE solve: nominal design (L, t, materials) and the physical change applied."""

    L_mm: float
    t_mm: float
    body: str = PAPER[0]
    membrane: str = PAPER[1]
    membrane_mu_scale: float = 1.0
    body_mu_scale: float = 1.0

    @property
    def key(self) -> str:
        return (f"{self.body}/{self.membrane} L{self.L_mm:g} t{self.t_mm:g}"
                f" m{self.membrane_mu_scale:g} b{self.body_mu_scale:g}")


PERTURBED_BASES = ((7.1, 0.75), (11.1, 0.5), (4.1, 0.5))  # solved in this order

# A curve that ends in a Newton failure is kept when it got this far: the labs' protocols
# read the curves to 25-40 ul, far below the volume at 60 deg of every case (50-130 ul).
# ``tests/calibration_lab.py`` refuses to read a curve past its last volume.
KEEP_FAILED_FROM_DEG = 60.0


def cases() -> list[CaseSpec]:
    out = [CaseSpec(L, t) for L in (4.1, 7.1, 11.1) for t in (0.5, 0.75)]
    out += [CaseSpec(7.1, 0.5, *REVERSED), CaseSpec(11.1, 0.5, *REVERSED)]
    for L, t in PERTURBED_BASES:
        out += [CaseSpec(L, t, membrane_mu_scale=1.3), CaseSpec(L, t, membrane_mu_scale=0.75),
                CaseSpec(L, round(t - 0.05, 6)), CaseSpec(round(L + 0.5, 6), t),
                CaseSpec(L, t, body_mu_scale=1.5)]
    return list(dict.fromkeys(out))


def design_of(case: CaseSpec):
    from solver.design import Design
    from solver.design_space import scaled_material

    return Design(L_mm=case.L_mm, t_mm=case.t_mm,
                  body_material=scaled_material(case.body, case.body_mu_scale),
                  membrane_material=scaled_material(case.membrane, case.membrane_mu_scale))


@dataclass(frozen=True)
class FECurve:
    case: CaseSpec
    pressure_pa: np.ndarray
    volume_ul: np.ndarray
    angle_deg: np.ndarray


def load(path: Path = PATH) -> tuple[dict[str, FECurve], dict]:
    """The cached curves by key, and the metadata (solver version, settings, date)."""
    with np.load(path, allow_pickle=False) as z:
        meta = json.loads(str(z["meta"]))
        out = {}
        for i, spec in enumerate(meta["cases"]):
            case = CaseSpec(**spec)
            out[case.key] = FECurve(case, z[f"p{i}"], z[f"v{i}"], z[f"a{i}"])
    return out, meta


def _save(curves: dict[str, FECurve], meta: dict, path: Path) -> None:
    arrays = {}
    meta = dict(meta, cases=[vars(c.case) for c in curves.values()])
    for i, c in enumerate(curves.values()):
        arrays[f"p{i}"] = c.pressure_pa.astype(np.float32)
        arrays[f"v{i}"] = c.volume_ul.astype(np.float32)
        arrays[f"a{i}"] = c.angle_deg.astype(np.float32)
    tmp = path.with_suffix(".tmp.npz")
    np.savez_compressed(tmp, meta=json.dumps(meta), **arrays)
    tmp.replace(path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fresh", action="store_true", help="solve every case again")
    args = parser.parse_args(argv)
    from solver import SolverSettings, solve
    from solver.store.record import git_commit, package_version

    settings = SolverSettings()
    meta = {"solver_package_version": package_version(), "git_commit": git_commit(),
            "settings": settings.as_dict(), "created_utc":
            datetime.now(UTC).isoformat(timespec="seconds"),
            "generator": "tests/fe_calibration_curves.py"}
    curves: dict[str, FECurve] = {}
    if PATH.exists() and not args.fresh:
        curves, old = load()
        if old.get("settings") != meta["settings"]:
            print("cached curves were made with other settings: use --fresh", file=sys.stderr)
            return 2
        meta = dict(old, updated_utc=meta["created_utc"])
    for case in cases():
        if case.key in curves:
            continue
        t0 = time.perf_counter()
        c = solve(design_of(case), settings)
        print(f"{case.key}: {c.status} ({c.reason}), {len(c)} steps, "
              f"{time.perf_counter() - t0:.0f} s", flush=True)
        reached_deg = float(np.max(np.abs(c.angle_deg))) if len(c) else 0.0
        if len(c) < 5 or (not c.converged and reached_deg < KEEP_FAILED_FROM_DEG):
            print(f"  skipped: {c.reason}", file=sys.stderr)
            continue
        curves[case.key] = FECurve(replace(case), np.asarray(c.pressure_pa),
                                   np.asarray(c.volume_ul), np.asarray(c.angle_deg))
        _save(curves, meta, PATH)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    raise SystemExit(main())
