"""The ``paper`` preset against the paper's own Tables 4 and 5.

Expected numbers: surrogate/exponential/paper_tables.py, transcribed from the reference paper
(Table 4: A per chamber length at tau = 420; Table 5: tau per membrane thickness at
A = 0.65; Eq. 6 constants a_t = 731.2, b_t = 7.179; a = 0.101). Tolerances are the
issue's: A within 10 %, tau within 3 %.
"""

import numpy as np
import pytest

from solver.design import Design
from surrogate import paper_surrogate
from surrogate.exponential.paper_tables import TABLE_4, TABLE_5, tau_from_paper_constants


@pytest.mark.parametrize(("L_mm", "A_printed"), [(row[0], row[1]) for row in TABLE_4])
def test_paper_preset_reproduces_table_4(L_mm: float, A_printed: float) -> None:
    params = paper_surrogate().family_parameters(Design(L_mm=L_mm))
    assert params["A_deg"] == pytest.approx(A_printed, rel=0.10)


@pytest.mark.parametrize(("t_mm", "tau_printed"), [(row[0], row[1]) for row in TABLE_5])
def test_paper_preset_reproduces_table_5(t_mm: float, tau_printed: float) -> None:
    params = paper_surrogate().family_parameters(Design(t_mm=t_mm))
    assert params["tau_pa"] == pytest.approx(tau_printed, rel=0.03)


def test_printed_ln_reading_of_eq_6_does_not_reproduce_table_5() -> None:
    # The discrepancy documented in docs/surrogate.md: ln gives tau more than twice Table 5.
    for t_mm, tau_printed, _, _ in TABLE_5:
        assert tau_from_paper_constants(t_mm, "ln") > 2.0 * tau_printed
        assert tau_from_paper_constants(t_mm, "log10") == pytest.approx(tau_printed, rel=0.03)


def test_paper_preset_standard_design_matches_the_papers_fit() -> None:
    # docs/notes: the paper's standard-curve fit angle = 0.704 (exp(p/420) - 1) gives
    # 6.9, 24.3, 81.6 deg at 1000, 1500, 2000 Pa; the preset's constants (A = 0.717,
    # tau = 405.8) must land within 25 % of them (tau differs by 3.4 %, amplified by p/tau);
    # at 2000 Pa the preset passes 90 deg, the end of the paper's curve: no number there.
    pred = paper_surrogate().predict(Design(), [1000.0, 1500.0, 2000.0])
    np.testing.assert_allclose(pred.angle_deg[:2], [6.9, 24.3], rtol=0.25)
    assert np.isnan(pred.angle_deg[2]) and "past_fe_range" in pred.validity["flags"]
    assert (pred.lower_deg[:2] < pred.angle_deg[:2]).all()
    assert (pred.angle_deg[:2] < pred.upper_deg[:2]).all()
    assert pred.model == "paper" and pred.form == "exponential"
