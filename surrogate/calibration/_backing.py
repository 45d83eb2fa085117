"""The baseline's own uncertainty, carried into the fitted parameters' standard errors:
its band where the fit reads the baseline, and its pressure scale at every fit.

A physical effect is read off the baseline at a changed design (a stiffer membrane, a
longer chamber). Where the baseline is uncertain there (an emulator's band at the changed
design), the size it gives is uncertain too, whatever the data say. Every other effect is
read off the baseline at the nominal designs, and its band there counts the same way: a
camera gain k x angle(V) is the data's bend over the baseline's, so an emulator whose
angle at the design is uncertain by 3 % leaves that gain uncertain by 3 % too (until
2026-12-07 only a physical change carried the band: on a lab's three Ecoflex specimens of
a membrane 10 % stiffer, the baseline's band 1.9 deg RMS at the nominal design, a camera
gain of 0.919 +/- 0.027 was selected at z 3.04, its sd without the band). The baseline's error
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

A second coherent error acts on every fit, whatever its effects: the baseline's pressure
scale. The FE the baseline stands in for reads the pressure at a given angle +0.4 to
+0.9 % above its mesh-converged value (default mesh, docs/verification.md), and a
design's nominal dimensions (written to 0.01 mm) move it by as much again, so the
baseline's pressure scale at each design is known to ``PRESSURE_SCALE_SD`` (relative sd),
independently between designs. Its direction is exact: a common pressure scale is what
scaling both layers' stiffness does (docs/surrogate.md, the invariance), so by pressure
the angle is read at p / (1 + e), and by injected volume the angle is unchanged and the
chamber pressure is (1 + e) p. A gauge gain or inlet resistance read off the gauge
channel is therefore uncertain by at least that much (a gauge reading 1 % high and two
layers 1 % stiffer than their presets are the same data).

A third acts on every size read off a physical change: the nominal dimensions. A lab
writes a design's L, t, T, b and h to some resolution (0.01 mm, or finer when it writes
more decimals), and its specimens' true dimensions lie anywhere within it. Each dimension
of each design is taken as uniform over its last written decimal (at most
``DIMENSION_RESOLUTION_MM``; sd = resolution / sqrt 12), independent of the others, and
its coherent direction is the baseline's own: the angle's change at every reading when
that dimension moves by its sd, at the fitted physical change (by pressure, as the band;
none on the gauge channel). A stiffer body of 0.988 +- 0.003 fitted on clean FE data
whose designs were written to 0.01 mm is that rounding, not a stiffer body.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from surrogate.calibration._least_squares import FitResult
from surrogate.calibration._response import Responses

PRESSURE_SCALE_SD = 0.01
DIMENSION_RESOLUTION_MM = 0.01          # the coarsest resolution a written dimension has
DIMENSIONS = ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm")


def resolution_mm(value: float) -> float:
    """The resolution (mm) a dimension written as ``value`` implies: its last decimal
    (the shortest text that reads back as the same number: 0.165 -> 0.001), at most
    DIMENSION_RESOLUTION_MM (1.0 and 1 are 0.01)."""
    text = repr(float(value))
    if "e" in text or "E" in text:
        return DIMENSION_RESOLUTION_MM
    decimals = len(text.split(".")[1].rstrip("0")) if "." in text else 0
    return min(10.0 ** -decimals, DIMENSION_RESOLUTION_MM)


def dimension_rows(f: FitResult, responses: Responses) -> list[np.ndarray]:
    """For each dimension, the angle's change (deg) at every reading when that dimension
    of every design moves by its resolution's sd, at the fitted physical change; [] when
    the fit changes no design."""
    m = f.model
    if not m.physical:
        return []
    values = f.values
    thetas = [values[e.parameters[0].name] for e in m.physical]
    at = m.reading_pressure(f.x)
    base = responses.angle_at(m.physical, thetas)
    out = []
    for name in DIMENSIONS:
        def moved(d, name=name):
            v = getattr(d, name)
            return replace(d, **{name: v + resolution_mm(v) / math.sqrt(12.0)})
        change = responses.angle_at(m.physical, thetas, moved) - base
        out.append(np.nan_to_num(responses.lookup(change, m.design_index, at), nan=0.0))
    return out


def baseline_sd_rows(f: FitResult, responses: Responses) -> np.ndarray:
    """The baseline's sd (deg) at every reading where the fit reads the baseline: at the
    fitted physical change, or at the nominal designs when the fit changes none."""
    m = f.model
    values = f.values
    table = (responses.sd_at(m.physical, [values[e.parameters[0].name] for e in m.physical])
             if m.physical else responses.nominal_sd())
    sd = responses.lookup(table, m.design_index, m.reading_pressure(f.x))
    return np.nan_to_num(sd, nan=0.0)


def with_baseline_uncertainty(f: FitResult, responses: Responses) -> FitResult:
    """``f`` with the baseline's own uncertainty in its covariance: its band where the
    fit reads it (every fit), the nominal dimensions' resolution (a physical change), and
    its pressure scale (every fit). ``baseline_sd_deg``: the band's RMS at a fitted
    physical change (None without one)."""
    if f.jac is None or not f.k:
        return f
    design = f.model.design_index
    if f.jac.shape[0] > design.size:   # the pressure channel's rows repeat the designs
        design = np.concatenate([design, design])
    m = f.model   # f.jac is of the weighted residuals (_specimens.py): so are the shifts
    cov = baseline_covariance(
        f.jac, m.whiten(PRESSURE_SCALE_SD * m.pressure_scale_direction(f.x)), design)
    s = baseline_sd_rows(f, responses)
    band_sd = float(np.sqrt(np.mean(s**2))) if m.physical else None   # the angle rows
    if f.jac.shape[0] > s.size:  # the pressure channel: no band for V(p) (0 there)
        s = np.concatenate([s, np.zeros(f.jac.shape[0] - s.size)])
    cov = cov + baseline_covariance(f.jac, m.whiten(s), design)
    for g in dimension_rows(f, responses):
        if f.jac.shape[0] > g.size:  # the pressure channel: none (as the band)
            g = np.concatenate([g, np.zeros(f.jac.shape[0] - g.size)])
        cov = cov + baseline_covariance(f.jac, m.whiten(g), design)
    return replace(f, cov=f.cov + cov, baseline_shift=np.sqrt(np.diag(cov)),
                   baseline_sd_deg=band_sd)


def baseline_covariance(jac: np.ndarray, s: np.ndarray, design: np.ndarray) -> np.ndarray:
    """sum_d delta_d delta_d', delta_d = (J'J)^-1 J_d' s_d: the baseline's error coherent
    within each design (index ``design`` per row), independent between designs."""
    bread = np.linalg.pinv(jac.T @ jac)
    g = np.zeros((int(design.max()) + 1, jac.shape[1]))
    np.add.at(g, design, jac * s[:, None])
    delta = g @ bread  # row d: delta_d' (bread is symmetric)
    return delta.T @ delta
