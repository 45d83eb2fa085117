"""Can these observations be calibrated? Checks made before any fit, so that data which
are valid but unusable give a DataError naming the column and what is needed.

* Cross-validation by curve needs at least ``MIN_CURVES`` = 2 curves (one to fit, one to
  predict). More folds than curves are reduced to the number of curves
  (leave-one-curve-out); the report states the folds requested and used.
* The starting model must be finite at every row: the model is exponential in p/tau, and
  gauge pressures beyond ``MAX_P_OVER_TAU`` = 300 tau (angle ~ A e^300 deg) are far
  outside anything it describes (the actuator works below about 5 tau).
"""

from __future__ import annotations

import numpy as np

from solver.errors import InputError
from surrogate.calibration._baseline import tau_pa
from surrogate.calibration._data import Observations
from surrogate.calibration._errors import DataError
from surrogate.calibration._forward import angle_model

MIN_CURVES = 2
MIN_FOLDS = 2
MAX_P_OVER_TAU = 300.0


def folds_used(folds: object, n_curves: int) -> int:
    """The number of folds of the cross-validation: ``folds`` (an integer >= 2) reduced
    to ``n_curves`` when there are fewer curves."""
    if isinstance(folds, bool) or not isinstance(folds, int | np.integer) or folds < MIN_FOLDS:
        raise InputError("folds", f"not an integer >= {MIN_FOLDS}: {folds!r}",
                         f"integer folds >= {MIN_FOLDS} (reduced to the number of curves)")
    return min(int(folds), n_curves)


def check_calibratable(obs: Observations, nominal: np.ndarray, folds: object) -> int:
    """Raise DataError/InputError if the loop cannot run on ``obs``; return the folds used."""
    if obs.n_curves < MIN_CURVES:
        ids = ", ".join(repr(c) for c in obs.curve_ids)
        raise DataError("curve_id", f"{obs.n_curves} curve ({ids}): cross-validation by "
                        "curve needs a second curve to predict", None,
                        f"at least {MIN_CURVES} curves (distinct curve_id); replicate "
                        "specimens of one design also give the noise floor")
    k = folds_used(folds, obs.n_curves)
    fam = np.asarray(nominal, dtype=float)[obs.family]
    tau = np.maximum(tau_pa(fam[:, 1], fam[:, 2], obs.t_mm), 1.0)
    ratio = obs.pressure_pa / tau
    pred = angle_model(obs, np.asarray(nominal, dtype=float), {})
    bad = (ratio > MAX_P_OVER_TAU) | ~np.isfinite(pred)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[np.argmax(ratio[bad])])
        raise DataError("pressure_pa", f"curve {obs.curve_ids[obs.curve[i]]!r}: "
                        f"{obs.pressure_pa[i]:g} Pa is {ratio[i]:.0f} x tau of the starting "
                        f"model (tau = {tau[i]:.0f} Pa at t_mm = {obs.t_mm[i]:g}), whose "
                        "angle there is not finite", None,
                        f"pressure_pa <= {MAX_P_OVER_TAU:g} tau = "
                        f"{MAX_P_OVER_TAU * tau[i]:.0f} Pa for this design")
    return k
