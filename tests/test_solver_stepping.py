"""The step control's speed-ups (extrapolating predictor, chord updates near the
solution) change how a step is converged, not where: the same curve to within the
Newton tolerance, with fewer factorisations."""

import numpy as np
import pytest

from solver import Design, SolverSettings, newton, stepping, stop_landing
from solver.hermite_predictor import Rate, State, predictor
from solver.stepping import solve

SMALL = SolverSettings(element="hex1", max_angle_deg=25)


def test_predictor_is_exact_on_a_quintic_through_three_states_and_their_tangents():
    def state(s):
        return (np.array([s, s**5 - 2 * s**3]), [np.array([2 * s * s - 1])], 3 * s**4 + s)

    def rate(s):
        return Rate(np.array([1.0, 5 * s**4 - 6 * s**2]), [np.array([4 * s])], 12 * s**3 + 1)

    history = [State(s, *state(s), rate(s)) for s in (0.0, 1.0, 1.5)]
    u, q, p = predictor(history, 2.2)
    eu, eq, ep = state(2.2)
    assert np.allclose(u, eu) and np.allclose(q[0], eq[0]) and p == pytest.approx(ep)
    # Without the middle state's tangent: a quartic, still exact on the quartic parts.
    history[1].rate = None
    u, q, p = predictor(history, 2.2)
    assert np.allclose(q[0], eq[0]) and p == pytest.approx(ep)
    assert not np.isclose(u[1], eu[1])
    # One state without its tangent: no extrapolation (Euler from the converged state).
    assert predictor([State(0.0, *state(0.0))], 2.2) is None
    # One state with it: the Euler predictor.
    u, q, p = predictor([State(1.0, *state(1.0), rate(1.0))], 1.5)
    assert p == pytest.approx(4.0 + 13.0 * 0.5)


def test_speed_ups_leave_the_converged_curve_unchanged(monkeypatch):
    fast = solve(Design(L_mm=4.1), SMALL)
    monkeypatch.setattr(newton, "CHORD_SWITCH", 0.0)      # full Newton every iteration
    for module in (stepping, stop_landing):   # restart each step (and landing step) from
        monkeypatch.setattr(module, "predictor", lambda history, load: None)   # the last state
    plain = solve(Design(L_mm=4.1), SMALL)
    assert fast.status == plain.status == "complete"
    # The same steps (the step control sees the same converged states): compare the
    # points whose injected volumes agree.
    pairs = [(i, int(np.argmin(np.abs(fast.volume_ul - v))))
             for i, v in enumerate(plain.volume_ul)]
    pairs = [(i, j) for i, j in pairs if abs(fast.volume_ul[j] - plain.volume_ul[i]) < 1e-6]
    assert len(pairs) >= 5
    i, j = np.array(pairs).T
    assert np.allclose(fast.pressure_pa[j], plain.pressure_pa[i], rtol=1e-6, atol=1e-6)
    assert np.allclose(fast.angle_deg[j], plain.angle_deg[i], rtol=1e-5, atol=1e-6)
    assert fast.timings_s["factorisations"] < 0.85 * plain.timings_s["factorisations"]


def test_a_cut_back_is_reported_with_the_last_converged_step(monkeypatch):
    """A job's page had shown 70 s at one pressure with nothing said (an audit of
    2026-12-06): every cut-back now reports the last converged step again with the count
    of cut-backs so far (the job's progress ``cutbacks``)."""
    calls = {"n": 0}
    original = stepping.mixed_newton_step

    def failing_once(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 4:
            raise stepping.StepFailed("made to fail once")
        return original(*args, **kwargs)

    monkeypatch.setattr(stepping, "mixed_newton_step", failing_once)
    infos: list[dict] = []
    curve = solve(Design(L_mm=4.1), SMALL, on_step=infos.append)
    assert curve.status in ("complete", "stopped")
    counts = [i["cutbacks"] for i in infos]
    assert counts == sorted(counts) and counts[-1] >= 1 and counts[0] == 0
    at = counts.index(1)
    assert infos[at]["step"] == infos[at - 1]["step"]          # the same converged step
    assert infos[at]["pressure_pa"] == infos[at - 1]["pressure_pa"]


def test_the_step_size_rule_grows_holds_and_limits_the_step():
    # solver/step_size.py's rule: 1.6 after <= 4 Newton solves, 1.0 after <= 7, else 0.6;
    # no more than 8 deg per step at the last step's rate, no more than max(150 Pa, 8 % of
    # p) per step under volume control, neither limit below half the last step.
    from solver.step_size import step_factor

    assert step_factor(4, 0.0, 0.0, 0.0, True) == 1.6
    assert step_factor(7, 0.0, 0.0, 0.0, True) == 1.0
    assert step_factor(8, 0.0, 0.0, 0.0, True) == 0.6
    assert step_factor(2, 10.0, 0.0, 0.0, True) == pytest.approx(0.8)       # 8 / 10 deg
    assert step_factor(2, 40.0, 0.0, 0.0, True) == 0.5                      # floor
    assert step_factor(2, 1.0, 300.0, 1000.0, True) == pytest.approx(0.5)   # 150 / 300 Pa
    assert step_factor(2, 1.0, 200.0, 2500.0, True) == 1.0                  # 8 % = 200 Pa
    assert step_factor(2, 1.0, 300.0, 1000.0, False) == 1.6                 # pressure control
