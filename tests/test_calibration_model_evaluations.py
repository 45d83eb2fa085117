"""One evaluation of the augmented model (surrogate/calibration/_augmented_model.py) does
each piece of its work once. A residual asks for the angles and for the gauge pressures at
the same parameters, and both read the line volume a leak left and the changed designs'
curves by volume; until 2026-12-07 each integrated the leak again (Heun along every
curve, most of a fit's time when a leak is among the candidates: the calibration of the
unseen set "radian-angles" spent 22 % of its CPU time on the repeat), and the chamber
pressure's curves were interpolated up to four times (``Responses.curves``). What is
kept must be what a fresh model gives, bit for bit, whatever parameters came in between.
"""

from __future__ import annotations

import numpy as np
import pytest
from calibration_lab import emulator
from test_calibration_history import lab_rows

from surrogate.calibration import _response, observations_from_rows
from surrogate.calibration._augmented_model import AugmentedModel
from surrogate.calibration._least_squares import pressure_residual
from surrogate.calibration._response import Responses, design_key
from surrogate.calibration.effects import EFFECTS


@pytest.fixture(scope="module")
def leak_model_parts():
    """Observations of a lab file with time and flow (a hold at a flat top), the
    emulator's responses at its design, and the effects: a stiffer body (a physical
    effect, read off the tables), a compliant line (the volume effect the leak's
    pressure is read through) and a leak."""
    obs = observations_from_rows(lab_rows("hold_at_a_flat_top")[0])
    designs = {design_key(obs.design(c)): obs.design(c) for c in range(obs.n_curves)}
    return obs, designs, (EFFECTS["body_stiffness"], EFFECTS["line_compliance"],
                          EFFECTS["chamber_leak"])


def _model(parts) -> AugmentedModel:
    """A fresh model: its own tables (nothing kept from another model's evaluations)."""
    obs, designs, effects = parts
    responses = Responses(emulator(), designs, 1.6 * float(obs.pressure_pa.max()) + 200.0,
                          1.25 * float(obs.volume_ul.max()) + 1.0)
    return AugmentedModel(obs, responses, effects, (), pressure_weight=0.01)


def _evaluation(model: AugmentedModel, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """What a residual evaluates: the angles, then the pressure channel (deg-equivalent)."""
    return model.angles(x), pressure_residual(model, x)


def test_one_residual_integrates_the_leak_once(leak_model_parts, monkeypatch):
    leak = type(EFFECTS["chamber_leak"])
    calls = []
    integrate = leak.delivered_volume

    def counted(self, *args, **kwargs):
        calls.append(1)
        return integrate(self, *args, **kwargs)

    monkeypatch.setattr(leak, "delivered_volume", counted)
    model = _model(leak_model_parts)
    assert model.by_volume and model._leaks
    _evaluation(model, model.layout.start.copy())
    assert len(calls) == 1


def test_one_residual_interpolates_each_curve_table_once(leak_model_parts, monkeypatch):
    """One physical effect: the chamber pressure and the angle by volume, each
    interpolated once along the effect's nodes (before: the pressure four times)."""
    model = _model(leak_model_parts)
    x = model.layout.start.copy()
    _evaluation(model, x)          # the tables built (their own interpolations aside)
    calls = []
    weights = _response.lagrange_weights

    def counted(*args):
        calls.append(1)
        return weights(*args)

    monkeypatch.setattr(_response, "lagrange_weights", counted)
    x[model.layout.names.index("body_mu_scale")] = 1.1
    _evaluation(model, x)
    assert len(calls) == 2


def test_what_is_kept_is_a_fresh_models_bit_for_bit(leak_model_parts):
    model = _model(leak_model_parts)
    names = model.layout.names
    x1 = model.layout.start.copy()
    x2 = x1.copy()
    x2[names.index("G_ul_s_per_kpa")] = 0.4
    x2[names.index("C_ul_per_kpa")] = 2.0
    x3 = x2.copy()
    x2[names.index("body_mu_scale")] = 1.2
    x3[names.index("G_ul_s_per_kpa")] = 0.41   # one parameter changed alone
    x4 = x3.copy()
    x4[names.index("body_mu_scale")] = 0.9
    for x in (x1, x2, x3, x1, x4, x3, x2):
        fresh = _evaluation(_model(leak_model_parts), x)
        kept = _evaluation(model, x)
        for a, b in zip(kept, fresh, strict=True):
            np.testing.assert_array_equal(a, b)
    # x changed in place after an evaluation: the next one sees the change
    x = x1.copy()
    _evaluation(model, x)
    x[names.index("G_ul_s_per_kpa")] = 0.4
    x[names.index("C_ul_per_kpa")] = 2.0
    x[names.index("body_mu_scale")] = 1.2
    for a, b in zip(_evaluation(model, x), _evaluation(_model(leak_model_parts), x2),
                    strict=True):
        np.testing.assert_array_equal(a, b)
