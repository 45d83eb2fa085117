"""The result of one solve: a pressure-volume-angle curve with per-step statistics."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

STATUSES = ("complete", "stopped", "failed")


@dataclass(frozen=True)
class Curve:
    """Per converged load step i (index 0 is the undeformed state):

    pressure_pa[i]            cavity pressure, Pa
    volume_ul[i]              injected volume = cavity volume change, whole actuator, ul (mm^3)
    time_s[i]                 volume_ul / flow_ul_s, s (the experiment's constant-flow clock)
    angle_deg[i]              bending angle: rotation of the free end face about y, degrees,
                              positive when the tip moves away from the membrane (+z)
    tip_displacement_mm[i]    displacement (x, z) of the free end face's centroid, mm
    max_membrane_stretch[i]   largest principal stretch in the membrane layer
    force_mn[i]               tip reaction (spring or block), whole actuator, mN; NaN if free
    newton_iterations[i]      Newton iterations of the step (0 for the first point)
    residual_norm[i]          final relative residual of the step
    negative_eigenvalues[i]   count of negative eigenvalues of the structural tangent at
                              fixed pressure (> 0: not positive definite, unstable under
                              pressure control); -1 when not computed

    volume_control_negative_eigenvalues[i]  (optional, None in records that predate it)
                              unstable modes at constant volume (the syringe pump): the
                              tangent's count less the limit point's (solver/stability.py);
                              > 0: a bifurcation, the curve follows an unstable branch

    status: "complete" (reached a stop criterion), "stopped" (ended early by a limit
    such as max_steps), or "failed" (a step could not converge); ``reason`` says why.
    ``pressure_maximum_index`` is the step of a pressure maximum under volume control
    (a limit point), or -1. ``branch_switch_index``: the step at which the solve left
    the unstable primary branch along its unstable mode (-1: never; points from it on
    lie on the stable secondary branch).
    """

    pressure_pa: np.ndarray
    volume_ul: np.ndarray
    time_s: np.ndarray
    angle_deg: np.ndarray
    tip_displacement_mm: np.ndarray
    max_membrane_stretch: np.ndarray
    force_mn: np.ndarray
    newton_iterations: np.ndarray
    residual_norm: np.ndarray
    negative_eigenvalues: np.ndarray
    status: str
    reason: str
    pressure_maximum_index: int = -1
    n_dofs: int = 0
    wall_time_s: float = 0.0
    timings_s: dict[str, float] = field(default_factory=dict)
    volume_control_negative_eigenvalues: np.ndarray | None = None
    branch_switch_index: int = -1

    ARRAY_FIELDS = ("pressure_pa", "volume_ul", "time_s", "angle_deg", "tip_displacement_mm",
                    "max_membrane_stretch", "force_mn", "newton_iterations", "residual_norm",
                    "negative_eigenvalues")

    def __len__(self) -> int:
        return int(self.pressure_pa.shape[0])

    @property
    def converged(self) -> bool:
        return self.status != "failed"

    def as_dict(self) -> dict[str, object]:
        """Plain-JSON view (lists of floats)."""
        out: dict[str, object] = {name: np.asarray(getattr(self, name)).tolist()
                                  for name in self.ARRAY_FIELDS}
        out.update(status=self.status, reason=self.reason,
                   pressure_maximum_index=self.pressure_maximum_index, n_dofs=self.n_dofs,
                   wall_time_s=self.wall_time_s, timings_s=dict(self.timings_s),
                   branch_switch_index=self.branch_switch_index)
        if self.volume_control_negative_eigenvalues is not None:
            out["volume_control_negative_eigenvalues"] = np.asarray(
                self.volume_control_negative_eigenvalues).tolist()
        return out

    def stability_notes(self) -> list[str]:
        """Plain-language notes on a loss of stability along the curve (empty if none):
        the first step whose tangent at fixed pressure is not positive definite (the
        actuator would snap under pressure control), the first step unstable at constant
        volume, a branch switch, and a pressure maximum under volume control."""
        notes = []
        unstable = np.nonzero(np.asarray(self.negative_eigenvalues) > 0)[0]
        if len(unstable):
            i = int(unstable[0])
            notes.append(
                f"tangent not positive definite from step {i} (p = {self.pressure_pa[i]:.0f} Pa,"
                f" angle = {self.angle_deg[i]:.1f} deg, {int(self.negative_eigenvalues[i])}"
                " negative eigenvalue(s)): unstable under pressure control")
        if self.volume_control_negative_eigenvalues is not None:
            vneg = np.asarray(self.volume_control_negative_eigenvalues)
            bif = np.nonzero(vneg > 0)[0]
            if len(bif):
                i = int(bif[0])
                notes.append(
                    f"unstable at constant volume too from step {i} (p = "
                    f"{self.pressure_pa[i]:.0f} Pa, angle = {self.angle_deg[i]:.1f} deg, "
                    f"{int(vneg[i])} volume-neutral mode(s)): a bifurcation, not a limit point;"
                    " the syringe-pump experiment would leave this branch")
        if self.branch_switch_index >= 0:
            i = self.branch_switch_index
            notes.append(f"left the primary branch at step {i} (angle = "
                         f"{self.angle_deg[i]:.1f} deg): past a bifurcation along its "
                         "unstable mode, or a snap over a fold in volume; later points "
                         "follow the branch reached (stable at constant volume where no "
                         "volume-neutral mode is flagged)")
        if self.pressure_maximum_index >= 0:
            i = self.pressure_maximum_index
            notes.append(f"pressure maximum {self.pressure_pa[i]:.0f} Pa at step {i} "
                         f"(angle = {self.angle_deg[i]:.1f} deg): a limit point")
        return notes

