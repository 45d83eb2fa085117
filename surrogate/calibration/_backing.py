"""The baseline's own uncertainty at a fitted physical change, carried into the fitted
parameters' standard errors.

A physical effect is read off the baseline at a changed design (a stiffer membrane, a
longer chamber). Where the baseline is uncertain there (an emulator's band at the changed
design), the size it gives is uncertain too, whatever the data say. The baseline's error
at one design is systematic: every specimen, flow rate and reading of that design shares
it (the emulator's band moves the whole curve: every node at +-z sd), so within a design it
shifts the fitted parameters coherently. Distinct nominal designs of the data are separate
points of the box, each with its own interpolation error, taken as independent of one
another (the ``Predictor`` protocol gives no covariance between designs). With s_d the
baseline's standard deviation at the readings of design d (its 95 % band / 1.96, at the
fitted design) and J the model's Jacobian at the fit,

    delta_d = (J'J)^-1 J_d' s_d,        cov_total = cov_data + sum_d delta_d delta_d'

(delta_d: the shift least squares makes when the baseline is off by one standard
deviation along its whole band at design d). Significance and the reported sd use
cov_total; ``sd_data`` and ``sd_baseline`` are reported apart.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from surrogate.calibration._least_squares import FitResult
from surrogate.calibration._response import Responses


def baseline_sd_rows(f: FitResult, responses: Responses) -> np.ndarray | None:
    """The baseline's sd (deg) at every reading, at the fitted physical change; None when
    the fit changes no design."""
    m = f.model
    if not m.physical:
        return None
    values = f.values
    table = responses.sd_at(m.physical, [values[e.parameters[0].name] for e in m.physical])
    sd = responses.lookup(table, m.design_index, m.reading_pressure(f.x))
    return np.nan_to_num(sd, nan=0.0)


def with_baseline_uncertainty(f: FitResult, responses: Responses) -> FitResult:
    """``f`` with the baseline's uncertainty at its fitted design in its covariance."""
    s = baseline_sd_rows(f, responses)
    if s is None or f.jac is None or not f.k:
        return f
    design = f.model.design_index
    if f.jac.shape[0] > s.size:  # the pressure channel: no band for V(p) (0 there)
        s = np.concatenate([s, np.zeros(f.jac.shape[0] - s.size)])
        design = np.concatenate([design, design])
    cov = baseline_covariance(f.jac, s, design)
    return replace(f, cov=f.cov + cov, baseline_shift=np.sqrt(np.diag(cov)),
                   baseline_sd_deg=float(np.sqrt(np.mean(s**2))))


def baseline_covariance(jac: np.ndarray, s: np.ndarray, design: np.ndarray) -> np.ndarray:
    """sum_d delta_d delta_d', delta_d = (J'J)^-1 J_d' s_d: the baseline's error coherent
    within each design (index ``design`` per row), independent between designs."""
    bread = np.linalg.pinv(jac.T @ jac)
    g = np.zeros((int(design.max()) + 1, jac.shape[1]))
    np.add.at(g, design, jac * s[:, None])
    delta = g @ bread  # row d: delta_d' (bread is symmetric)
    return delta.T @ delta
