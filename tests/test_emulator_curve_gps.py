"""The curve GPs' volume nodes above the anchor, read as the log of their rise in log V."""


import numpy as np
import pytest

from surrogate.emulator.curve_gps import (
    CurveGPs,
    anchor_index,
    node_outputs,
    rise_outputs,
)
from surrogate.emulator.features import ANGLE_NODES_DEG
from surrogate.emulator.vector_gp import MEANS_ONLY, fit_output_gps

N = len(ANGLE_NODES_DEG)


def _node_rows(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Inputs in the unit square and node outputs of curves whose injected volume grows
    with the angle, faster above 60 deg the larger the first input (as a membrane that
    balloons near its pressure maximum)."""
    rng = np.random.default_rng(seed)
    u = rng.random((n, 2))
    theta = ANGLE_NODES_DEG
    log_p = np.log(200.0 + 20.0 * theta) - np.log(theta) + 0.3 * u[:, :1]
    log_vol = (np.log(0.5 + 0.4 * theta) + 0.2 * u[:, 1:]
               + 2.0 * u[:, :1] * np.clip(theta - 60.0, 0.0, None) / 30.0)
    return u, np.hstack((log_p, log_vol - np.log(theta)))


def test_the_rise_and_its_inverse_return_the_node_outputs():
    _, y = _node_rows(20)
    a = anchor_index()
    assert ANGLE_NODES_DEG[a] == 30.0
    z = rise_outputs(y, a)
    np.testing.assert_array_equal(z[:, :N + a + 1], y[:, :N + a + 1])   # untouched
    assert not np.allclose(z[:, N + a + 1:], y[:, N + a + 1:])
    back, var = node_outputs(z, np.zeros_like(z), a)
    np.testing.assert_allclose(back, y, atol=1e-12)
    np.testing.assert_array_equal(var, 0.0)
    assert rise_outputs(y, None) is not y and np.array_equal(rise_outputs(y, None), y)


def test_the_top_nodes_variance_is_the_anchors_and_the_rises_to_first_order():
    _, y = _node_rows(1)
    a = anchor_index()
    z = rise_outputs(y[0], a)
    var = np.full(2 * N, 1e-6)
    rng = np.random.default_rng(1)
    draws = z + rng.standard_normal((200_000, 2 * N)) * np.sqrt(var)
    sampled = node_outputs(draws, np.zeros_like(draws), a)[0].var(axis=0)
    _, first_order = node_outputs(z, var, a)
    np.testing.assert_allclose(first_order, sampled, rtol=0.03)
    # NaN (not asked) stays NaN; the anchor's NaN makes its top nodes NaN
    var[N + a] = np.nan
    _, out = node_outputs(z, var, a)
    assert np.isnan(out[N + a:]).all() and np.isfinite(out[:N + a]).all()


def test_curve_gps_reproduce_their_training_curves_and_ask_the_anchors_variance():
    u, y = _node_rows(30)
    a = anchor_index()
    cg = CurveGPs(fit_output_gps(u, rise_outputs(y, a), shared=slice(0, N)), a)
    mean, var = cg.predict_many(u)
    np.testing.assert_allclose(mean, y, atol=2e-3)
    # a query asking only the top volume nodes' variance gets it (the anchor's is read
    # for it) and NaN for every other output
    top = np.arange(N + a + 1, 2 * N)
    m1, v1 = cg.predict(u[3], variance_of=top)
    np.testing.assert_allclose(m1, mean[3], atol=1e-9)
    np.testing.assert_allclose(v1[top], var[3, top], rtol=1e-5, atol=1e-12)
    assert np.isnan(np.delete(v1, top)).all()
    assert np.isnan(cg.predict_many(u[:2], variance_of=MEANS_ONLY)[1]).all()


def test_an_emulator_file_keeps_the_anchor_and_refuses_a_damaged_one(
        shipped_emulator_saved_and_loaded):
    from surrogate.emulator.file import emulator_from_dict, emulator_to_dict
    from surrogate.errors import SurrogateFileError
    from surrogate.file_seal import KEY

    e, loaded = shipped_emulator_saved_and_loaded
    pe = next(iter(e.pairs.values()))
    assert pe.curves.volume_rise_anchor == anchor_index()
    assert loaded.pairs[pe.pair].curves.volume_rise_anchor == anchor_index()
    d = emulator_to_dict(e)    # each damaged copy checked in memory, as the file's loader does
    d.pop(KEY)
    for bad in (N - 1, -1, 3.0, "19", True):
        d["pairs"][0]["volume_rise_anchor"] = bad
        with pytest.raises(SurrogateFileError, match="volume_rise_anchor"):
            emulator_from_dict(d, "damaged.json")


def test_a_gp_far_from_its_designs_gives_a_bounded_rise_and_band():
    """The rise and its sd are capped at MAX_LOG_RISE: a query at a corner of the unit
    cube, where the GPs' linear means extrapolate, gets finite volumes and bands."""
    from surrogate.emulator import load_emulator
    from surrogate.emulator.curve_gps import MAX_LOG_RISE

    a = anchor_index()
    z = np.zeros(2 * N)
    z[N + a + 1:] = 4000.0
    var = np.full(2 * N, 1e6)
    mean, out = node_outputs(z, var, a)
    lv = mean[N:] + np.log(ANGLE_NODES_DEG)
    np.testing.assert_allclose(lv[a + 1:] - lv[a], MAX_LOG_RISE)
    assert (out[N + a + 1:] <= var[N + a] + MAX_LOG_RISE**2 + 1e-9).all()
    e = load_emulator("service/data/emulator.json")
    corners = np.array(np.meshgrid(*[[0.0, 1.0]] * 6)).reshape(6, -1).T
    for pe in e.pairs.values():
        m, v = pe.curves.predict_many(corners)
        top = m[:, N + a + 1:] + np.log(ANGLE_NODES_DEG[a + 1:])
        assert np.isfinite(m).all() and np.isfinite(v).all(), pe.pair
        assert (top - (m[:, [N + a]] + np.log(ANGLE_NODES_DEG[a])) <= MAX_LOG_RISE + 1e-9).all()
