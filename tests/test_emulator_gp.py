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
    designs) and by a packed single-precision BLAS product per output above
    (``_shifted_variance``); predict_many by blocks of CHUNK_ROWS. Every path, with the
    variance asked of some outputs or of none, gives the same numbers (the variance of
    the single-precision path to 1e-3)."""
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
        # the single-precision path: to 1e-7 of each output's prior variance
        atol = 1e-14 if n <= SMALL_N else 1e-7 * prior_variance(vgp)[some].max()
        for i in (0, CHUNK_ROWS + 3):
            m1, v1 = vgp.predict(test[i], variance_of=some)
            np.testing.assert_allclose(m1, mean[i], rtol=1e-10)
            np.testing.assert_allclose(v1[some], var[i, some], rtol=1e-7, atol=atol)
            m0, v0 = vgp.predict(test[i], variance_of=MEANS_ONLY)
            np.testing.assert_allclose(m0, mean[i], rtol=1e-10)
            assert np.isnan(v0).all()


def test_a_kernels_inverse_is_made_on_its_first_variance_and_matches_the_solve():
    """L^-1 of a kernel is made when a variance first needs it (``VectorGP._linv_t``), not
    when the GPs are built or loaded, and only for the kernels asked; the variance it
    gives is the GP's own by triangular solves (``GaussianProcess.predict``)."""
    from surrogate.emulator.vector_gp import MEANS_ONLY, SMALL_N

    rng = np.random.default_rng(5)
    for n in (SMALL_N // 3, SMALL_N + 40):
        u = rng.uniform(size=(n, 3))
        vgp = vector_gp_from_dict(fit_output_gps(u, curves(u)).as_dict())
        made = vgp._stack["linv_t"]
        assert made == {}
        q = rng.uniform(size=3)
        vgp.predict(q, variance_of=MEANS_ONLY)
        vgp.predict_many(q[None, :], variance_of=MEANS_ONLY)
        assert made == {} and vgp._stack["gram"] == {}      # nor K, which a variance reads
        some = np.array([2, 5])
        _, var = vgp.predict(q, variance_of=some)
        assert sorted(made) == sorted(int(vgp._stack["kernel"][j]) for j in some)
        assert sorted(vgp._stack["gram"]) == ([] if n <= SMALL_N else sorted(made))
        for j in some:
            _, v_gp = vgp.gps[j].predict(q[None, :])
            expected = vgp.scale[j] ** 2 * v_gp[0] + vgp.residual_var[j]
            atol = 1e-14 if n <= SMALL_N else 1e-7 * prior_variance(vgp)[j]
            np.testing.assert_allclose(var[j], expected, rtol=1e-7, atol=atol)


def prior_variance(vgp) -> np.ndarray:
    """Each output's prior variance (output units): what a band is read against."""
    return np.array([gp.signal_var for gp in vgp.gps]) * vgp.scale**2


def test_the_single_precision_variance_holds_at_and_near_the_data():
    """A single query's variance in single precision (``_shifted_variance``) against the
    double-precision batch, where it is hardest: at database designs (a variance of
    ~1e-10 of the prior's), 1e-4 and 1e-2 away, and beyond the data. These GPs are far
    worse conditioned than the emulator's (length scales at the bound of 20, nugget
    1e-10); the error stays below 1e-5 of the prior variance (3e-3 of its sd; measured
    4e-6, beyond the data). The direct form 1 - |L^-1 k|^2 in single precision is off by
    whole prior variances."""
    from surrogate.emulator.vector_gp import SMALL_N

    rng = np.random.default_rng(11)
    u = rng.uniform(size=(SMALL_N + 60, 3))
    vgp = fit_output_gps(u, curves(u))
    queries = np.vstack((u[:20], u[20:40] + 1e-4 * rng.standard_normal((20, 3)),
                         u[40:60] + 1e-2 * rng.standard_normal((20, 3)),
                         rng.uniform(-0.2, 1.2, size=(20, 3))))
    _, var = vgp.predict_many(queries)
    single = np.array([vgp.predict(q)[1] for q in queries])
    prior = prior_variance(vgp)
    assert (var[:20] < 1e-8 * prior).all()           # the hard case is there
    np.testing.assert_allclose(single[:40], var[:40], rtol=1e-2, atol=1e-11 * prior.max())
    np.testing.assert_allclose(single, var, rtol=1e-2, atol=1e-5 * prior.max())


def _dense_neg_reml(params: np.ndarray, x: np.ndarray, y: np.ndarray) -> float:
    """The restricted likelihood written out on dense matrices (the textbook form):
    1/2 [(n - p) log s2 + log|K| + log|H^T K^-1 H|], s2 = y^T P y / (n - p)."""
    n, d = x.shape
    lengths, nugget = np.exp(params[:d]), np.exp(params[d])
    r = np.sqrt((((x[:, None, :] - x[None, :, :]) / lengths) ** 2).sum(-1))
    k = (1 + np.sqrt(5) * r + 5 / 3 * r**2) * np.exp(-np.sqrt(5) * r) + nugget * np.eye(n)
    h = np.column_stack((np.ones(n), x))
    kinv = np.linalg.inv(k)
    hk = h.T @ kinv @ h
    p = kinv - kinv @ h @ np.linalg.inv(hk) @ h.T @ kinv
    s2 = y @ p @ y / (n - h.shape[1])
    return 0.5 * ((n - h.shape[1]) * np.log(s2) + np.linalg.slogdet(k)[1]
                  + np.linalg.slogdet(hk)[1])


def test_the_restricted_likelihood_and_its_gradient_against_the_dense_form():
    # _neg_reml works on the pairs i > j and LAPACK's packed factorisation: its value is
    # the dense form's, and its gradient the dense form's central differences
    from surrogate.emulator.gp import TrainingPairs, _neg_reml

    rng = np.random.default_rng(3)
    x = rng.uniform(size=(40, 3))
    y = curves(x)[:, 3] + 0.01 * rng.standard_normal(40)
    pairs = TrainingPairs.of(x)
    for params in (np.log([0.6, 0.6, 0.6, 1e-6]), np.log([0.3, 1.5, 0.8, 1e-3])):
        value, grad = _neg_reml(params, x, y, pairs)
        assert value == _neg_reml(params, x, y)[0]       # pairs computed on the fly alike
        np.testing.assert_allclose(value, _dense_neg_reml(params, x, y), rtol=1e-9)
        step = 1e-5
        numeric = [(_dense_neg_reml(params + step * e, x, y)
                    - _dense_neg_reml(params - step * e, x, y)) / (2 * step)
                   for e in np.eye(len(params))]
        np.testing.assert_allclose(grad, numeric, rtol=1e-4, atol=1e-6)


def test_outputs_sharing_one_kernel_fit_their_summed_likelihood_and_share_the_variance():
    """fit_output_gps(shared=...): the columns of ``shared`` get one kernel (lengths and
    nugget) that maximises the sum of their restricted likelihoods (its gradient: the
    dense form's central differences, summed over the columns); each keeps its own signal
    variance and mean and interpolates its designs. A query's variance of those columns is
    one product (``kernels``), and equals each column's own GP's variance on every path."""
    from surrogate.emulator.gp import TrainingPairs, _neg_reml
    from surrogate.emulator.vector_gp import SMALL_N

    rng = np.random.default_rng(5)
    x = rng.uniform(size=(40, 3))
    y = curves(x)[:, 2:6]
    params = np.log([0.5, 1.1, 0.7, 1e-5])
    value, grad = _neg_reml(params, x, y, TrainingPairs.of(x))
    np.testing.assert_allclose(value, sum(_dense_neg_reml(params, x, y[:, j])
                                          for j in range(4)), rtol=1e-9)
    step = 1e-5
    numeric = [sum(_dense_neg_reml(params + step * e, x, y[:, j])
                   - _dense_neg_reml(params - step * e, x, y[:, j]) for j in range(4))
               / (2 * step) for e in np.eye(len(params))]
    np.testing.assert_allclose(grad, numeric, rtol=1e-4, atol=1e-6)

    for n in (SMALL_N // 3, SMALL_N + 40):
        u = rng.uniform(size=(n, 3))
        vgp = fit_output_gps(u, curves(u), shared=slice(0, 6))
        gps = vgp.gps
        assert all(np.array_equal(g.lengths, gps[0].lengths) and g.nugget == gps[0].nugget
                   for g in gps[:6])
        assert vgp.kernels(slice(0, 6)) == 1 and vgp.kernels(slice(None)) == 3
        np.testing.assert_allclose(vgp.predict_many(u)[0], curves(u), atol=1e-3)
        test = rng.uniform(size=(5, 3))
        mean, var = vgp.predict_many(test)
        own = np.array([[g.predict(test)[1][i] for g in gps] for i in range(5)])
        np.testing.assert_allclose(var, own * vgp.scale**2, rtol=1e-8, atol=1e-14)
        atol = 1e-14 if n <= SMALL_N else 1e-7 * prior_variance(vgp).max()
        for i in range(5):
            m1, v1 = vgp.predict(test[i], variance_of=np.arange(8))
            # the two paths sum the kernel row in other orders: 1e-12 apart on outputs of
            # order 1 (a mean near 0 was 1.4e-10 apart relatively on another CPU)
            np.testing.assert_allclose(m1, mean[i], rtol=1e-10, atol=1e-11)
            np.testing.assert_allclose(v1, var[i], rtol=1e-7, atol=atol)
        # read back from its file form, the shared kernel is factorised once
        again = vector_gp_from_dict(vgp.as_dict())
        assert all(g.chol is again.gps[0].chol for g in again.gps[1:6])
        assert again.gps[6].chol is not again.gps[0].chol
        m2, v2 = again.predict_many(test)
        np.testing.assert_array_equal(m2, mean)
        np.testing.assert_array_equal(v2, var)
