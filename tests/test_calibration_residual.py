"""The allowance of the cross-validated error over the replicate floor
(surrogate/calibration/_residual.py): both are measured on the same few curves."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from surrogate.calibration._noise import NoiseFloor
from surrogate.calibration._residual import EXCESS_RATIO, cv_rel_se, excess_limit


def _obs(n_curves: int, per_curve: int) -> SimpleNamespace:
    return SimpleNamespace(n_curves=n_curves, curve=np.repeat(np.arange(n_curves), per_curve))


def test_the_cross_validated_errors_own_uncertainty_counts_curves_not_readings():
    rng = np.random.default_rng(0)
    obs = _obs(9, 20)
    white = rng.standard_normal(180)                    # scatter independent per reading
    shared = np.repeat(rng.standard_normal(9), 20) + 0.1 * rng.standard_normal(180)
    # a specimen's offset shared along its curve: 9 independent units, not 180
    assert cv_rel_se(obs, shared) > 3 * cv_rel_se(obs, white)
    # mean squares 1, 4, 9, ... per curve: the spread of the per-curve values over sqrt(9),
    # halved for the root, relative to the mean square
    steps = np.repeat(np.arange(1, 10, dtype=float), 20)
    ms = np.arange(1, 10, dtype=float) ** 2
    expected = 0.5 * np.std(ms, ddof=1) / 3.0 / ms.mean()
    assert math.isclose(cv_rel_se(obs, steps), expected, rel_tol=1e-12)
    assert math.isnan(cv_rel_se(_obs(1, 20), white[:20]))    # one curve: unknown


def test_the_allowance_adds_both_relative_errors_and_never_falls_below_the_ratio():
    floor = NoiseFloor(1.0, 100, "replicates", 3, rel_se=0.12)
    assert math.isclose(excess_limit(floor), 1.24)
    assert math.isclose(excess_limit(floor, 0.16), 1.0 + 2 * 0.2)
    assert excess_limit(NoiseFloor(1.0, 100, "replicates", 3, rel_se=0.01), 0.01) == EXCESS_RATIO
    assert math.isclose(excess_limit(NoiseFloor(1.0, 100, "replicates", 3)), EXCESS_RATIO)
