"""What the half model's symmetry plane hides: the actuator on the full width (issue 12).

The solver meshes y >= 0 with u_y = 0 on y = 0, so it cannot see a mode antisymmetric in
y. This check solves a design on the full width (``build_mesh(..., full_width=True)``,
the half mesh's divisions mirrored, no symmetry condition, only the clamped end), with
the solver's own stepping, and reports the curve and the lowest volume-neutral modes at
the last state with the share of each that is symmetric in y (u_x, u_z even, u_y odd).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/full_width_check.py --t-mm 0.25 --max-steps 40
    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/full_width_check.py --t-mm 0.5

Results (2026-12-02, default mesh, hex2, 19125 dofs) are in docs/physics.md ("What the half
model cannot see").
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from solver import Design, SolverSettings
from solver.discrete import ActuatorModel, Evaluation, SolidModel
from solver.linear import factorize
from solver.mesh import build_mesh
from solver.stability import constrained_modes
from solver.stepping import inflate_model


class FullWidthActuator(SolidModel):
    """The whole actuator: clamped at x = 0, free tip, no symmetry plane."""

    def __init__(self, design: Design, settings: SolverSettings) -> None:
        self.design = design.validated()
        self.settings = settings
        am = build_mesh(self.design, settings.mesh_level, full_width=True)
        groups = [(np.nonzero(~am.membrane)[0], self.design.body_material, False),
                  (np.nonzero(am.membrane)[0], self.design.membrane_material, True)]

        def clamped(X: np.ndarray) -> np.ndarray:
            return np.repeat((X[0] < 1e-9)[:, None], 3, axis=1)

        super().__init__(am.mesh, settings.element, groups, am.cavity_facets, clamped,
                         settings.bulk_ratio)
        self.end_nodes = np.nonzero(np.abs(self.doflocs[0] - am.end_face_x_mm) < 1e-9)[0]

    end_face_kinematics = ActuatorModel.end_face_kinematics

    def injected_volume_ul(self, volume_mm3: float) -> float:
        return volume_mm3 - self.volume0_mm3           # the whole cavity

    def tip_force_mn(self, ev: Evaluation) -> float:
        return float("nan")


def symmetric_share(model: SolidModel, phi: np.ndarray) -> float:
    """Share of |phi|^2 in its part symmetric about y = 0."""
    X = model.doflocs
    index = {tuple(np.round(x, 9)): i for i, x in enumerate(X.T)}
    mirror = np.array([index[(round(a, 9), round(-b, 9) + 0.0, round(c, 9))]
                       for a, b, c in np.round(X.T, 9)])
    U = model.full(phi).reshape(-1, 3)
    sym = 0.5 * (U + U[mirror] * np.array([1.0, -1.0, 1.0]))
    return float(np.linalg.norm(sym) ** 2 / np.linalg.norm(U) ** 2)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-mm", type=float, default=0.5)
    ap.add_argument("--max-steps", type=int, default=80)
    ap.add_argument("--modes", type=int, default=4)
    args = ap.parse_args()
    settings = SolverSettings(max_steps=args.max_steps)
    model = FullWidthActuator(Design(t_mm=args.t_mm), settings)
    t0 = time.perf_counter()
    curve, u = inflate_model(model, settings)
    print(f"t = {args.t_mm} mm, {model.n_free} dofs, {time.perf_counter() - t0:.0f} s: "
          f"{curve.status} ({curve.reason})")
    for i in range(len(curve)):
        print(f"{i:3d} p = {curve.pressure_pa[i]:8.2f} Pa  V = {curve.volume_ul[i]:7.3f} ul  "
              f"angle = {curve.angle_deg[i]:6.2f} deg  neg(K) = {curve.negative_eigenvalues[i]}"
              f"  unstable at constant V = {curve.volume_control_negative_eigenvalues[i]}")
    ev = model.evaluate(u, float(curve.pressure_pa[-1]), pressures=model.consistent_pressures(u))
    vals, vecs = constrained_modes(ev.K, ev.g, factorize(ev.K), k=args.modes)
    for lam, phi in zip(vals, vecs.T):
        print(f"volume-neutral mode {lam:.4g} uN/mm: symmetric share in y "
              f"{symmetric_share(model, phi):.4f}")


if __name__ == "__main__":
    main()
