"""The baseline's own uncertainty at a fitted physical change, carried into the fitted
parameters' standard errors.

A physical effect is read off the baseline at a changed design (a stiffer membrane, a
longer chamber). Where the baseline is uncertain there (an emulator's band at the changed
design), the size it gives is uncertain too, whatever the data say. The band is a
systematic error shared by every reading of the design, so it moves the fitted
parameters coherently: with s the baseline's standard deviation at each reading (its 95 %
band / 1.96, at the fitted design) and J the model's Jacobian at the fit,

    delta = (J'J)^-1 J' s,        cov_total = cov_data + delta delta'

(the shift least squares makes when the baseline is off by one standard deviation along
its whole band). Significance and the reported sd use cov_total; ``sd_data`` and
``sd_baseline`` are reported apart.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from surrogate.calibration._fit import FitResult
from surrogate.calibration._response import Responses


def baseline_sd_rows(f: FitResult, responses: Responses) -> np.ndarray | None:
    """The baseline's sd (deg) at every reading, at the fitted physical change; None when
    the fit changes no design."""
    m = f.model
    if not m.physical:
        return None
    values = f.values
    table = responses.sd_at(m.physical, [values[e.parameters[0].name] for e in m.physical])
    sd = responses.lookup(table, m.design_index, np.clip(m.obs.pressure_pa, 0.0, None))
    return np.nan_to_num(sd, nan=0.0)


def with_baseline_uncertainty(f: FitResult, responses: Responses) -> FitResult:
    """``f`` with the baseline's uncertainty at its fitted design in its covariance."""
    s = baseline_sd_rows(f, responses)
    if s is None or f.jac is None or not f.k:
        return f
    delta = np.linalg.pinv(f.jac.T @ f.jac) @ (f.jac.T @ s)
    return replace(f, cov=f.cov + np.outer(delta, delta), baseline_shift=delta,
                   baseline_sd_deg=float(np.sqrt(np.mean(s**2))))
