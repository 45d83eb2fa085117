"""Specimen-to-specimen scatter as a random effect: least squares weighted the way the
readings scatter (generalised least squares).

Specimens of one design differ in stiffness by a few per cent (mixing, curing, moulding),
so each curve's whole pressure scale is off by its own e_c ~ N(0, tau^2). Read against
the gauge pressure, that scatter is one shift per curve along the direction

    g_c = d angle / d e   (AugmentedModel.pressure_scale_direction)

-- large where the curve is steep, nothing at zero pressure -- on top of independent
reading noise sigma. A curve's residuals therefore have covariance

    Sigma_c = sigma^2 I + tau^2 g_c g_c'

and ordinary least squares, which weighs every reading alike, lets the 4-deg specimen
scatter at 60 deg swamp what the readings near zero pressure say plainly (an angle
offset: 2.2 +/- 0.85 deg for 2.5 on PDMS 1:10 curves without time_s, where the specimens'
3 % stiffness scatter makes a 3.5 deg floor). Least squares on whitened residuals
W_c r_c is the GLS estimate, with

    W_c = I - beta_c u_c u_c',   u_c = g_c / |g_c|,
    beta_c = 1 - sigma / sqrt(sigma^2 + tau^2 |g_c|^2)

(W_c' W_c = sigma^2 Sigma_c^-1: residuals stay in degrees, and tau = 0 is ordinary least
squares). tau and sigma are estimated once, from the recalibrated baseline's residuals
(method of moments): each curve's own scale a_c = g_c' r_c / g_c' g_c scatters within its
replicate group (one design at one flow rate) with variance tau^2 + sigma^2 / |g_c|^2,
and what is left after it gives sigma^2. A common misfit of the baseline (every curve of a
design off alike) is not scatter: only the spread within a group counts. Without two
replicates in some group tau is 0 (no weighting).

Used where the angle is read against the gauge pressure; by injected volume a specimen's
stiffness does not move the angle (it moves the gauge, the pressure channel), and the
loop there is unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TAU_MAX = 0.3  # a specimen's pressure scale scatters by less than 30 %


@dataclass(frozen=True)
class SpecimenScatter:
    """tau: relative sd of a specimen's pressure scale; sigma_deg: reading noise (deg);
    groups: replicate groups (>= 2 curves) it was estimated from."""

    tau: float
    sigma_deg: float
    groups: int

    def whiten(self, r: np.ndarray, g: np.ndarray, curve: np.ndarray) -> np.ndarray:
        """W r, curve by curve (``g`` the pressure-scale direction per row, ``curve`` the
        curve of each row)."""
        if self.tau <= 0.0 or self.sigma_deg <= 0.0:
            return r
        n = int(curve.max()) + 1
        gg = np.bincount(curve, weights=g * g, minlength=n)
        gr = np.bincount(curve, weights=g * r, minlength=n)
        beta = 1.0 - self.sigma_deg / np.sqrt(self.sigma_deg**2 + self.tau**2 * gg)
        coef = np.where(gg > 0.0, beta * gr / np.where(gg > 0.0, gg, 1.0), 0.0)
        return r - coef[curve] * g

    def as_dict(self) -> dict[str, float | int]:
        return {"pressure_scale_sd": self.tau, "reading_sd_deg": self.sigma_deg,
                "replicate_groups": self.groups}


def specimen_scatter(r: np.ndarray, g: np.ndarray, curve: np.ndarray, group: np.ndarray
                     ) -> SpecimenScatter:
    """tau and sigma from residuals ``r`` (deg) of the recalibrated baseline, the
    pressure-scale direction ``g`` (deg per unit relative scale), and each row's curve and
    replicate group (see the module's docstring)."""
    ok = np.isfinite(r) & np.isfinite(g)
    r, g, curve, group = np.where(ok, r, 0.0), np.where(ok, g, 0.0), curve, group
    n = int(curve.max()) + 1
    gg = np.bincount(curve, weights=g * g, minlength=n)
    gr = np.bincount(curve, weights=g * r, minlength=n)
    rows = np.bincount(curve, weights=ok.astype(float), minlength=n)
    scaled = gg > 1e-12
    a = np.where(scaled, gr / np.where(scaled, gg, 1.0), 0.0)
    left = r - a[curve] * g
    dof = ok.sum() - int(scaled.sum())
    if dof <= 0:
        return SpecimenScatter(0.0, float("nan"), 0)
    sigma2 = float(np.sum(left[ok] ** 2) / dof)
    group_of = np.full(n, -1)
    group_of[curve] = group
    spread, dof_a, noise, groups = 0.0, 0, [], 0
    for gi in np.unique(group_of[scaled & (rows > 0)]):
        members = np.flatnonzero((group_of == gi) & scaled & (rows > 0))
        if members.size < 2:
            continue
        groups += 1
        spread += float(np.sum((a[members] - a[members].mean()) ** 2))
        dof_a += members.size - 1
        noise.extend((sigma2 / gg[members]).tolist())
    if not groups:
        return SpecimenScatter(0.0, float(np.sqrt(sigma2)), 0)
    tau2 = spread / dof_a - float(np.mean(noise))
    tau = float(np.sqrt(min(max(tau2, 0.0), TAU_MAX**2)))
    return SpecimenScatter(tau, float(np.sqrt(sigma2)), groups)
