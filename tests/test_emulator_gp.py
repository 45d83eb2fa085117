"""The emulator's per-output Gaussian processes (surrogate/emulator/vector_gp.py,
``fit_output_gps``) on a synthetic vector function whose values are known exactly."""

from __future__ import annotations

import numpy as np

from surrogate.emulator.vector_gp import fit_output_gps, vector_gp_from_dict

NODES = np.linspace(0.0, 1.0, 8)


def curves(u: np.ndarray) -> np.ndarray:
    """A smooth family of 8-node 'curves' over three inputs: the first nodes follow one
    input, the last ones another (as a curve's low-angle stiffness and its plateau depend
    on different lengths)."""
    w = NODES[None, :]
    return (1 - w) * np.sin(3 * u[:, :1]) + w * np.cos(2.5 * u[:, 1:2]) + 0.3 * u[:, 2:3] * w**2


def test_one_gp_per_output_interpolates_its_designs_with_honest_bands():
    rng = np.random.default_rng(0)
    u = rng.uniform(size=(30, 3))
    y = curves(u)
    vgp = fit_output_gps(u, y)
    assert len(vgp.gps) == y.shape[1]
    np.testing.assert_array_equal(vgp.components, np.eye(y.shape[1]))
    # the database designs are reproduced (FE values, not noisy measurements)
    np.testing.assert_allclose(vgp.predict_many(u)[0], y, atol=1e-3)
    test = rng.uniform(size=(300, 3))
    mean, var = vgp.predict_many(test)
    err = mean - curves(test)
    assert np.sqrt(np.mean(err**2)) < 0.01 * np.ptp(y)
    inside = np.abs(err) <= 1.96 * np.sqrt(var)
    assert 0.9 <= inside.mean()
    # one row at a time gives the same as many at once, and the file round trip too
    m1, v1 = vgp.predict(test[0])
    np.testing.assert_allclose(m1, mean[0], rtol=1e-10)
    np.testing.assert_allclose(v1, var[0], rtol=1e-7, atol=1e-12 * y.var())
    again = vector_gp_from_dict(vgp.as_dict())
    np.testing.assert_allclose(again.predict_many(test)[0], mean, rtol=1e-10, atol=1e-12)


def test_a_single_query_and_the_batch_agree_on_both_variance_paths():
    """VectorGP.predict reads L^-1 k by one batched product for small groups (<= SMALL_N
    designs) and by a packed BLAS product per output above; predict_many by blocks of
    CHUNK_ROWS. Every path, with the variance asked of some outputs or of none, gives the
    same numbers."""
    from surrogate.emulator.vector_gp import CHUNK_ROWS, MEANS_ONLY, SMALL_N

    rng = np.random.default_rng(3)
    for n in (SMALL_N // 3, SMALL_N + 40):
        u = rng.uniform(size=(n, 3))
        vgp = fit_output_gps(u, curves(u))
        test = rng.uniform(size=(CHUNK_ROWS + 7, 3))
        mean, var = vgp.predict_many(test)
        some = np.array([0, 3, 7])
        m_some, v_some = vgp.predict_many(test, variance_of=some)
        np.testing.assert_allclose(m_some, mean, rtol=1e-12)
        np.testing.assert_allclose(v_some[:, some], var[:, some], rtol=1e-9, atol=1e-14)
        assert np.isnan(v_some[:, 1]).all()
        for i in (0, CHUNK_ROWS + 3):
            m1, v1 = vgp.predict(test[i], variance_of=some)
            np.testing.assert_allclose(m1, mean[i], rtol=1e-10)
            np.testing.assert_allclose(v1[some], var[i, some], rtol=1e-7, atol=1e-14)
            m0, v0 = vgp.predict(test[i], variance_of=MEANS_ONLY)
            np.testing.assert_allclose(m0, mean[i], rtol=1e-10)
            assert np.isnan(v0).all()
