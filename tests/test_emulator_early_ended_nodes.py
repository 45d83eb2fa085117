"""The early-ended database curves' node values, blended in for designs that end early."""


import numpy as np
import pytest

from surrogate.emulator.curve_gps import CurveGPs
from surrogate.emulator.early_ended_nodes import (
    BLEND_DEG,
    ConditionedMeans,
    EarlyEndedRows,
    early_weight,
    short_of_the_end,
)
from surrogate.emulator.gp import from_hyperparameters
from surrogate.emulator.vector_gp import MEANS_ONLY, fit_output_gps

N = 32


def _rows(n: int, m: int, outputs: int = 6, seed: int = 0):
    """Complete rows (n) and early-ended rows (m, reaching the first k outputs) of a smooth
    function of three inputs whose early-ended rows sit a little off it (their own shape
    near their end), with the pattern of a curve that stops: reached outputs, then NaN."""
    rng = np.random.default_rng(seed)
    u = rng.random((n, 3))
    ue = rng.random((m, 3))

    def f(x: np.ndarray) -> np.ndarray:
        j = np.arange(outputs)
        return np.sin(2 * x[:, :1] + 0.3 * j) + x[:, 1:2] * j / outputs - 0.5 * x[:, 2:]

    reach = rng.integers(1, outputs + 1, m)
    ye = f(ue) + 0.05
    ye[np.arange(outputs)[None, :] >= reach[:, None]] = np.nan
    return u, f(u), ue, ye


def test_each_curve_loses_its_last_reached_node_where_the_last_fe_step_holds_it():
    """The nodes are ANGLE_NODES_DEG's first four here (0.1, 0.2, 0.3, 0.5 deg)."""
    y = np.full((4, 8), np.nan)
    y[0, :4] = y[0, 4:] = 1.0           # reaches all 4 nodes, last step from 0.4 deg
    y[1, :2] = y[1, 4:6] = 2.0          # reaches 2, last step from 0.15
    y[2, :1] = y[2, 4:5] = 3.0          # reaches 1, last step from 0: nothing left
    y[3, :3] = y[3, 4:7] = 4.0          # reaches 3 (0.3 deg); its last step from 0.31 deg
    out = short_of_the_end(y, 4, np.array([0.4, 0.15, 0.0, 0.31]))
    np.testing.assert_array_equal(np.isfinite(out).sum(1), [6, 2, 0, 6])
    assert np.isnan(out[0, 3]) and np.isnan(out[0, 7]) and np.isnan(out[1, [1, 5]]).all()
    np.testing.assert_array_equal(out[3], y[3])   # the node lies below the last step: kept
    assert np.isfinite(y).sum() == 20   # the input is left alone


def test_the_weight_is_one_below_the_blend_zero_above_linear_between():
    lo, hi = BLEND_DEG
    np.testing.assert_allclose(early_weight([lo - 30, lo, 0.5 * (lo + hi), hi, 90.0]),
                               [1.0, 1.0, 0.5, 0.0, 0.0])


def test_conditioned_means_are_each_outputs_gp_on_its_complete_and_reaching_rows():
    """Against the GP conditioned directly on the rows each output has (the complete
    rows and the early-ended ones that reach it), hyperparameters kept: shared kernels
    (one factor, its leading blocks) and own kernels alike."""
    u, y, ue, ye = _rows(40, 15)
    vgp = fit_output_gps(u, y, shared=slice(0, 3))          # 3 share a kernel, 3 their own
    cond = ConditionedMeans(vgp, EarlyEndedRows(ue, ye))
    q = np.random.default_rng(5).random((7, 3))
    got = cond.predict_many(q)
    np.testing.assert_allclose(cond.predict(q[4]), got[4], rtol=1e-7, atol=1e-8)
    for j, g in enumerate(vgp.gps):
        reach = np.isfinite(ye[:, j])
        zj = (ye[reach, j] - vgp.center[j]) / vgp.scale[j]
        direct = from_hyperparameters(np.vstack((u, ue[reach])), np.concatenate((g.y, zj)),
                                      g.lengths, g.nugget)
        np.testing.assert_allclose(got[:, j], vgp.center[j] + vgp.scale[j]
                                   * direct.predict(q)[0], rtol=1e-7, atol=1e-9)
    # at an early-ended row it gives that row's values where the row reaches
    at = cond.predict_many(ue)
    reach = np.isfinite(ye)
    np.testing.assert_allclose(at[reach], ye[reach], atol=1e-3)


def test_rows_that_do_not_stop_like_a_curve_are_refused():
    u, y, ue, ye = _rows(20, 4)
    bad = ye.copy()
    bad[0, :] = 1.0
    bad[0, 2] = np.nan          # a gap: reached, not reached, reached
    with pytest.raises(ValueError, match="first nodes"):
        EarlyEndedRows(ue, bad)
    with pytest.raises(ValueError, match="same m"):
        EarlyEndedRows(ue[:3], ye)
    rows = EarlyEndedRows(ue, ye)        # ordered by how far each reaches
    reach = np.isfinite(rows.y).sum(1)
    assert (np.diff(reach) <= 0).all()


def test_the_blend_moves_the_means_and_adds_its_spread_to_the_variance():
    """mean = m0 + w (m1 - m0), variance = v0 + w (m1 - m0)^2: the complete-curve GPs'
    variance and the two means' disagreement, as far as the blend reaches."""
    u, y, ue, ye = _rows(40, 15)
    vgp = fit_output_gps(u, y, shared=slice(0, 6))
    plain = CurveGPs(vgp)
    with_rows = CurveGPs(vgp, None, EarlyEndedRows(ue, ye))
    q = np.random.default_rng(2).random((5, 3))
    m0, v0 = plain.predict_many(q)
    m_off, v_off = with_rows.predict_many(q, early_weight=np.zeros(5))
    np.testing.assert_array_equal(m_off, m0)
    np.testing.assert_array_equal(v_off, v0)
    w = np.array([0.0, 0.25, 0.5, 1.0, 0.0])
    m_w, v_w = with_rows.predict_many(q, early_weight=w)
    m1 = with_rows._conditioned.predict_many(q)
    np.testing.assert_allclose(m_w, (1 - w[:, None]) * m0 + w[:, None] * m1, atol=1e-12)
    # (the GP variance is read in single precision, vector_gp: a few 1e-7 relative)
    np.testing.assert_allclose(v_w, v0 + w[:, None] * (m1 - m0) ** 2, rtol=1e-6, atol=1e-10)
    assert (v_w[w == 0] == v0[w == 0]).all()
    single, single_var = with_rows.predict(q[2], early_weight=0.5)
    np.testing.assert_allclose(single, m_w[2], atol=1e-12)
    np.testing.assert_allclose(single_var, v_w[2], rtol=1e-3)   # single precision there
    means_only, nan_var = with_rows.predict(q[2], variance_of=MEANS_ONLY, early_weight=0.5)
    np.testing.assert_allclose(means_only, m_w[2], atol=1e-12)
    assert np.isnan(nan_var).all()             # a variance not asked stays not asked


def test_the_shipped_emulator_reproduces_its_early_ended_curves_where_they_end_early():
    """At every early-ended database design its group's range model emulates to end below
    BLEND_DEG[0], a query's node outputs are that curve's own FE node values where the
    curve reaches (the database designs reproduced, early-ended ones included)."""
    from surrogate.emulator import load_emulator

    e = load_emulator("service/data/emulator.json")
    checked = 0
    for pe in e.pairs.values():
        rows = pe.curves.early_ended
        assert rows is not None and len(rows.u) > 0, pe.pair
        for u, y in zip(rows.u, rows.y, strict=True):
            mean, _, end, _ = pe.curve_nodes(u, variance_of=MEANS_ONLY)
            if end[0] >= BLEND_DEG[0]:
                continue
            reach = np.isfinite(y[:N])
            np.testing.assert_allclose(mean[:N][reach], y[:N][reach], atol=2e-3)
            checked += 1
    assert checked >= 20


def test_an_emulator_file_keeps_the_rows_reads_format_10_and_refuses_damage(
        shipped_emulator_saved_and_loaded):
    from surrogate.emulator.file import emulator_from_dict, emulator_to_dict
    from surrogate.errors import SurrogateFileError
    from surrogate.file_seal import KEY

    e, loaded = shipped_emulator_saved_and_loaded
    pe = next(iter(e.pairs.values()))
    back = loaded.pairs[pe.pair]
    np.testing.assert_array_equal(back.curves.early_ended.u, pe.curves.early_ended.u)
    np.testing.assert_array_equal(back.curves.early_ended.y, pe.curves.early_ended.y)

    # the file's validation is emulator_from_dict's: each damaged copy is checked in
    # memory (writing and reading 30 MB per copy cost ~10 s each and tested nothing more)
    d = emulator_to_dict(e)
    d.pop(KEY)
    rows = d["pairs"][0]["early_ended_nodes"]
    gap = [list(r) for r in rows["y"]]
    gap[0][1] = None                                        # reached, not, reached
    for bad in ("rows", {"u": rows["u"]}, {"u": rows["u"][:-1], "y": rows["y"]},
                {"u": [[2.0] * 6] * len(rows["u"]), "y": rows["y"]},
                {"u": rows["u"], "y": [r[:10] for r in rows["y"]]},
                {"u": rows["u"], "y": gap}):
        d["pairs"][0]["early_ended_nodes"] = bad
        with pytest.raises(SurrogateFileError, match="early_ended_nodes|same m|first nodes"):
            emulator_from_dict(d, "damaged.json")
    d["pairs"][0]["early_ended_nodes"] = rows
    d["format_version"] = 10
    for p in d["pairs"]:
        p.pop("early_ended_nodes")
    old = emulator_from_dict(d, "old.json")
    assert all(p.curves.early_ended is None for p in old.pairs.values())
