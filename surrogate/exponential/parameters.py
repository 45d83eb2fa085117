"""One family's parameter set of one model form (fitted, or the paper's published
constants), with its covariance, residual-scatter model and band scale; plain-JSON form
and its reader (format versions 1 and 2 of the surrogate file)."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from surrogate.exponential import equations


def parameter_variance(gradient: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """g C g^T for every row of ``gradient`` (..., k)."""
    return np.sum((gradient @ covariance) * gradient, axis=-1)


@dataclass(frozen=True)
class ModelParameters:
    """A fitted (or published) parameter set of one form for one family.

    ``values`` follow ``names`` (b_t in 1/mm); ``covariance`` is that of the fit
    coordinates ``covariance_names`` (log10 b_t in place of b_t, see
    ``surrogate.exponential.equations``; use ``parameter_variance`` for g C g^T with
    g = d / d values); ``fixed`` names
    parameters held constant (zero variance); residual scatter sd(angle) =
    sqrt(residual_sd^2 + (residual_rel angle)^2) in the model's unit (deg for angle, mN
    for force). ``rmse``/``max_error`` are the in-sample errors of the fit,
    ``n_points``/``n_curves`` its data. ``band_scale`` (>= 1) multiplies every band's
    half-width: it is calibrated on held-out designs (``band_scale_from_lodo``) because
    model-form error is correlated along a curve and the in-sample scatter model alone
    gives bands that are too narrow."""

    form: str
    names: tuple[str, ...]
    values: tuple[float, ...]
    covariance: tuple[tuple[float, ...], ...]
    residual_sd: float
    residual_rel: float
    fixed: tuple[str, ...] = ()
    rmse: float | None = None
    max_error: float | None = None
    n_points: int = 0
    n_curves: int = 0
    source: str = "fit"
    extra: dict = field(default_factory=dict)
    band_scale: float = 1.0

    @cached_property
    def theta(self) -> np.ndarray:
        return np.asarray(self.values, dtype=float)

    @cached_property
    def cov(self) -> np.ndarray:
        """Covariance of the fit coordinates (``covariance_names``)."""
        return np.asarray(self.covariance, dtype=float).reshape(len(self.values),
                                                                len(self.values))

    @property
    def covariance_names(self) -> tuple[str, ...]:
        return equations.FIT_NAMES[self.form]

    @property
    def standard_errors(self) -> dict[str, float]:
        """sqrt of the covariance's diagonal, by ``covariance_names``."""
        se = np.sqrt(np.clip(np.diag(self.cov), 0.0, None))
        return {n: float(v) for n, v in zip(self.covariance_names, se, strict=True)}

    def parameter_variance(self, gradient: np.ndarray) -> np.ndarray:
        """g C g^T for a gradient (..., k) in ``values`` (d / d b_t in the b_t column)."""
        return parameter_variance(equations.gradient_to_fit(gradient, self.theta), self.cov)

    def as_dict(self) -> dict[str, object]:
        return {"form": self.form, "names": list(self.names), "values": list(self.values),
                "covariance_names": list(self.covariance_names),
                "covariance": [list(r) for r in self.covariance],
                "standard_errors": self.standard_errors,
                "residual_sd": self.residual_sd, "residual_rel": self.residual_rel,
                "fixed": list(self.fixed), "rmse": self.rmse, "max_error": self.max_error,
                "n_points": self.n_points, "n_curves": self.n_curves, "source": self.source,
                "extra": dict(self.extra), "band_scale": self.band_scale}


COVARIANCE_IN_LOG10_B_T_SINCE = 2  # surrogate file format versions before: b_t in 1/mm


def parameters_from_dict(d: dict, format_version: int = COVARIANCE_IN_LOG10_B_T_SINCE
                         ) -> ModelParameters:
    """From ``as_dict``; a covariance written by format version 1 (in b_t, 1/mm) is
    converted to the fit coordinates (``equations.covariance_from_b_t``: same bands)."""
    values = tuple(float(v) for v in d["values"])
    cov = np.array(d["covariance"], dtype=float).reshape(len(values), len(values))
    fit_names = equations.FIT_NAMES[d["form"]]
    if format_version < COVARIANCE_IN_LOG10_B_T_SINCE:
        cov = equations.covariance_from_b_t(cov, np.array(values))
    elif tuple(d.get("covariance_names", fit_names)) != fit_names:
        raise ValueError(f"covariance_names {d['covariance_names']!r} are not {fit_names}")
    return ModelParameters(
        form=d["form"], names=tuple(d["names"]), values=values,
        covariance=tuple(tuple(float(v) for v in r) for r in cov),
        residual_sd=float(d["residual_sd"]), residual_rel=float(d["residual_rel"]),
        fixed=tuple(d.get("fixed", ())), rmse=d.get("rmse"), max_error=d.get("max_error"),
        n_points=int(d.get("n_points", 0)), n_curves=int(d.get("n_curves", 0)),
        source=d.get("source", "fit"), extra=dict(d.get("extra", {})),
        band_scale=float(d.get("band_scale", 1.0)))
