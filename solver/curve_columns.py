"""The curve as the stepping writes it: one row per converged state, reported as it comes,
made into a ``Curve`` at the end.

Each row holds the cavity pressure (Pa), the injected volume of the whole actuator (ul),
the bending angle (deg) and the tip's displacement (mm) of the end face, the largest
membrane stretch, the tip force (mN), the step's Newton solves and residual, and the
tangent's negative eigenvalues under pressure control and at constant volume
(solver/stability.py). A row can be taken back (a step replaced by a branch switch or by
its landing on a stop).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from solver.curve import Curve
from solver.discrete import Evaluation
from solver.settings import SolverSettings
from solver.stability import volume_control_index

COLUMNS = ("pressure_pa", "volume_ul", "angle_deg", "tip_displacement_mm",
           "max_membrane_stretch", "newton_iterations", "residual_norm",
           "negative_eigenvalues", "force_mn", "volume_control_negative_eigenvalues")


class CurveColumns:
    """The rows of a curve being solved on ``model`` (an ``ActuatorModel`` or a reference
    problem with its kinematics, solver/stepping.py), each reported to ``on_step``."""

    def __init__(self, model: Any, on_step: Callable[[dict], None] | None):
        self.model = model
        self.on_step = on_step
        self.columns: dict[str, list] = {name: [] for name in COLUMNS}

    def __len__(self) -> int:
        return len(self.columns["pressure_pa"])

    def last(self, name: str, back: int = 1) -> Any:
        """The column ``name``'s value ``back`` rows from the end (1: the last row)."""
        return self.columns[name][-back]

    def append(self, u: np.ndarray, pressure_pa: float, newton_solves: int, residual: float,
               negative_pivots: int, evaluation: Evaluation, g_kinv_g: float = 1.0) -> float:
        """A converged state (displacement u in mm, cavity pressure in Pa) as a row, reported;
        returns its bending angle (deg). ``g_kinv_g`` = dV/dp (mm^3/Pa) gives the count of
        unstable modes at constant volume from the tangent's (-1: not computed)."""
        angle, tip = self.model.end_face_kinematics(u)
        row = self.columns
        row["volume_control_negative_eigenvalues"].append(
            volume_control_index(negative_pivots, g_kinv_g) if negative_pivots >= 0
            else negative_pivots)
        row["pressure_pa"].append(pressure_pa)
        row["volume_ul"].append(self.model.injected_volume_ul(evaluation.volume_mm3))
        row["angle_deg"].append(angle)
        row["tip_displacement_mm"].append(tip)
        row["max_membrane_stretch"].append(evaluation.max_membrane_stretch)
        row["newton_iterations"].append(newton_solves)
        row["residual_norm"].append(residual)
        row["negative_eigenvalues"].append(negative_pivots)
        row["force_mn"].append(self.model.tip_force_mn(evaluation))
        self.report()
        return angle

    def drop_last(self) -> None:
        """The last row taken back (its step is replaced)."""
        for column in self.columns.values():
            column.pop()

    def report(self) -> None:
        """The last converged step to ``on_step``, with the cut-backs so far: after every
        converged step and after every cut-back (a job's page then says why the curve
        stands still: 70 s at one pressure had looked like a hang); a step landed on a
        stop is reported again under the same number as the step past it it replaces."""
        if self.on_step is not None and len(self) > 1:
            self.on_step({"step": len(self) - 1, "pressure_pa": self.last("pressure_pa"),
                          "volume_ul": self.last("volume_ul"),
                          "angle_deg": self.last("angle_deg"),
                          "newton_iterations": self.last("newton_iterations"),
                          "cutbacks": int(self.model.timings.get("cutbacks", 0))})

    def curve(self, settings: SolverSettings, status: str, reason: str, switch_index: int,
              wall_time_s: float) -> Curve:
        """The rows as a ``Curve``; its time axis is the injected volume at the settings'
        flow rate (s), its pressure maximum the first fall of the pressure under volume
        control (a limit point; -1: none)."""
        row = self.columns
        pressure = np.array(row["pressure_pa"])
        pmax = -1
        if settings.control == "volume" and len(pressure) > 2:
            drops = np.nonzero(np.diff(pressure) < 0)[0]
            if len(drops):
                pmax = int(drops[0])
        volume = np.array(row["volume_ul"])
        n = len(pressure)
        return Curve(
            pressure_pa=pressure, volume_ul=volume, time_s=volume / settings.flow_ul_s,
            angle_deg=np.array(row["angle_deg"]),
            tip_displacement_mm=np.array(row["tip_displacement_mm"]).reshape(n, 2),
            max_membrane_stretch=np.array(row["max_membrane_stretch"]),
            force_mn=np.array(row["force_mn"]),
            newton_iterations=np.array(row["newton_iterations"], dtype=np.int64),
            residual_norm=np.array(row["residual_norm"]),
            negative_eigenvalues=np.array(row["negative_eigenvalues"], dtype=np.int64),
            status=status, reason=reason, pressure_maximum_index=pmax,
            n_dofs=self.model.n_free, wall_time_s=wall_time_s,
            timings_s=dict(self.model.timings),
            volume_control_negative_eigenvalues=np.array(
                row["volume_control_negative_eigenvalues"], dtype=np.int64),
            branch_switch_index=switch_index)
