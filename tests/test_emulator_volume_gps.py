"""The volume nodes read with the pressure curve's shape among their GPs' inputs
(``surrogate.emulator.volume_gps``): the leave-one-out means they are fitted on, what the
shape buys where the volume is a steep function of it, and the emulator file's field."""

import json

import numpy as np
import pytest

from surrogate.emulator.curve_gps import CurveGPs, anchor_index, rise_outputs
from surrogate.emulator.features import ANGLE_NODES_DEG
from surrogate.emulator.gp import from_hyperparameters
from surrogate.emulator.vector_gp import MEANS_ONLY, fit_output_gps
from surrogate.emulator.volume_gps import (
    fit_volume_gps,
    loo_pressure_means,
    pressure_shape,
    shape_scaling,
    volume_gps_from_dict,
)

N = len(ANGLE_NODES_DEG)


def _rows(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Designs in the unit cube (3 inputs) and node outputs of curves whose pressure
    flattens above 30 deg by an amount s(u), and whose injected volume above 30 deg rises
    sharply once s passes 0.6 (a membrane nearing its pressure maximum balloons)."""
    rng = np.random.default_rng(seed)
    u = rng.random((n, 3))
    s = u @ np.array([[1.0], [0.65], [0.3]]) / 1.95                       # in [0, 1]
    theta = ANGLE_NODES_DEG
    top = np.clip(theta - 30.0, 0.0, None) / 60.0
    log_p = (np.log(300.0 + 10.0 * theta) - np.log(theta) + 0.2 * u[:, 2:]
             - 0.5 * s * top - 0.1 * u[:, 1:2] * np.log(theta)
             + 0.3 * np.sin(3.0 * u[:, :1]) * top)
    log_v = (np.log(0.5 + 0.3 * theta) - np.log(theta) + 0.1 * u[:, :1]
             + (0.1 + 2.0 / (1.0 + np.exp(-25.0 * (s - 0.6)))) * top)
    return u, np.hstack((log_p, log_v))


def test_the_leave_one_out_means_are_those_of_the_gp_refitted_without_the_row():
    u, y = _rows(25, seed=1)
    gp = fit_output_gps(u, y[:, :N], shared=slice(0, N))
    loo = loo_pressure_means(gp, N)
    for i in (0, 7, 24):
        keep = np.arange(len(u)) != i
        for j in (0, 20, N - 1):
            g = gp.gps[j]
            refit = from_hyperparameters(g.x[keep], g.y[keep], g.lengths, g.nugget)
            z = refit.predict(g.x[i:i + 1])[0][0]
            assert loo[i, j] == pytest.approx(gp.center[j] + gp.scale[j] * z, abs=1e-8)
    # a VectorGP of principal components has no per-output leave-one-out here
    from surrogate.emulator.vector_gp import fit_vector_gp
    with pytest.raises(ValueError, match="one GP per output"):
        loo_pressure_means(fit_vector_gp(u, y[:, :N]), N)


def test_the_fitted_designs_curves_are_reproduced_on_both_axes():
    """At a fitted design the query's shape is corrected to the leave-one-out shape the
    volume GPs were fitted on, so they give back its own volume outputs (as the pressure
    GPs give back its pressure outputs); the correction fades away from the designs."""
    a = anchor_index()
    u, y = _rows(40, seed=6)
    z = rise_outputs(y, a)
    gp = fit_output_gps(u, z, shared=slice(0, N))
    volume = fit_volume_gps(u, z[:, N:], gp)
    cg = CurveGPs(gp, a, None, volume)
    np.testing.assert_allclose(cg.predict_many(u, variance_of=MEANS_ONLY)[0], y, atol=2e-3)
    x = volume.gp.gps[0].x
    p_mean = gp.predict_many(u, variance_of=MEANS_ONLY)[0][:, :N]
    np.testing.assert_allclose(volume.inputs(u, p_mean), x, atol=1e-4)
    # uncorrected, the fitted designs' shape inputs are not the ones fitted on
    scaled = (pressure_shape(p_mean) - volume.shape_low) / volume.shape_span
    assert np.abs(scaled - x[:, 3:]).max() > 1e-3
    far = np.full((1, 3), 5.0)             # far outside the unit cube: no correction left
    p_far = gp.predict_many(far, variance_of=MEANS_ONLY)[0][:, :N]
    np.testing.assert_allclose(volume.inputs(far, p_far)[0, 3:],
                               ((pressure_shape(p_far) - volume.shape_low)
                                / volume.shape_span)[0], atol=1e-9)


def test_one_query_and_a_batch_agree_and_the_variance_is_the_volume_gps():
    a = anchor_index()
    u, y = _rows(40, seed=4)
    z = rise_outputs(y, a)
    gp = fit_output_gps(u, z, shared=slice(0, N))
    volume = fit_volume_gps(u, z[:, N:], gp)
    cg = CurveGPs(gp, a, None, volume)
    q = np.random.default_rng(5).random((6, 3))
    mean, var = cg.predict_many(q)
    for i in range(len(q)):
        m1, v1 = cg.predict(q[i])
        np.testing.assert_allclose(m1, mean[i], rtol=1e-9, atol=1e-12)
        # a single query's variance: L^-1 in single precision (VectorGP.predict)
        np.testing.assert_allclose(v1, var[i], rtol=1e-4, atol=1e-12)
    # the anchor node's variance is the volume GPs' own at the pressure means' shape
    p_mean = gp.predict_many(q, variance_of=MEANS_ONLY)[0][:, :N]
    _, v_var = volume.predict_many(q, p_mean)
    np.testing.assert_allclose(var[:, N + a], v_var[:, a], rtol=1e-6)
    # asking only the top nodes' variance gives theirs (the anchor read for them), NaN else
    top = np.arange(N + a + 1, 2 * N)
    m2, v2 = cg.predict(q[0], variance_of=top)
    np.testing.assert_allclose(v2[top], var[0, top], rtol=1e-4)
    assert np.isnan(np.delete(v2, top)).all()
    assert cg.kernels(slice(0, N)) == 1
    assert cg.kernels(slice(N, 2 * N)) == volume.gp.kernels(slice(None)) >= 2
    assert pressure_shape(p_mean).shape == (6, 3)


def test_damaged_stored_volume_gps_are_refused_by_field():
    good = {"shape_low": [0.0, 0.1, 0.2], "shape_span": [1.0, 1.0, 1.0],
            "pressure_lengths": [0.5] * 7, "shape_alpha": [[0.0, 0.1, 0.2]] * 4}
    assert [a.shape for a in shape_scaling(good)] == [(3,), (3,), (7,), (4, 3)]
    for field, value in (("shape_low", [0.0, 1.0]), ("shape_span", [1.0, 0.0, 1.0]),
                         ("shape_span", [1.0, float("inf"), 1.0]),
                         ("pressure_lengths", [-1.0] * 7), ("pressure_lengths", 1.0),
                         ("shape_alpha", [0.0, 0.0, 0.0]), ("shape_alpha", [[0.0, 0.0]]),
                         ("shape_alpha", [[0.0, float("nan"), 0.0]]), ("shape_low", None),
                         ("shape_low", "abc")):
        with pytest.raises(ValueError, match="volume_gps"):
            shape_scaling({**good, field: value})


def test_the_emulator_file_keeps_the_volume_gps_and_refuses_them_damaged(tmp_path):
    from surrogate.emulator import load_emulator
    from surrogate.emulator.file import FORMAT_VERSION, emulator_to_dict
    from surrogate.errors import SurrogateFileError
    from surrogate.file_seal import KEY

    e = load_emulator("service/data/emulator.json")
    assert FORMAT_VERSION >= 13
    assert all(pe.curves.volume is not None for pe in e.pairs.values())
    pe = next(iter(e.pairs.values()))
    # the stored form gives back the same answers (the whole file's round trip:
    # test_emulator_balance.py; this one builds one pair's volume GPs, not every GP)
    back = volume_gps_from_dict(json.loads(json.dumps(pe.curves.volume.as_dict())))
    u = pe.coordinates[:3] + 0.01
    p_mean = pe.curves.predict_many(u, variance_of=MEANS_ONLY)[0][:, :N]
    for a, b in zip(back.predict_many(u, p_mean), pe.curves.volume.predict_many(u, p_mean),
                    strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12)

    def write(d: dict) -> str:
        out = tmp_path / "other.json"     # unsealed: a file without a checksum is read
        out.write_text(json.dumps(d))
        return str(out)

    d = emulator_to_dict(e)               # one copy, each change undone after its load
    d.pop(KEY, None)
    # a format-12 file has none: the volume nodes are the curve GPs' own
    d["format_version"] = 12
    stored = [p.pop("volume_gps") for p in d["pairs"]]
    old = load_emulator(write(d))
    d["format_version"] = FORMAT_VERSION
    for p, v in zip(d["pairs"], stored, strict=True):
        p["volume_gps"] = v
    assert all(p.curves.volume is None for p in old.pairs.values())
    design = old.pairs[pe.pair].coordinates[0]
    m_old = old.pairs[pe.pair].curves.predict(design, variance_of=MEANS_ONLY)[0]
    m_new = e.pairs[pe.pair].curves.predict(design, variance_of=MEANS_ONLY)[0]
    np.testing.assert_allclose(m_old[:N], m_new[:N], rtol=1e-9)   # the same pressure GPs

    volume = d["pairs"][0]["volume_gps"]
    damage = [("shape_span", [1.0, -1.0, 1.0]), ("gp", "x"), ("pressure_lengths", [1.0]),
              ("shape_alpha", "x")]
    for field, value in damage:
        kept, volume[field] = volume[field], value
        with pytest.raises(SurrogateFileError, match="volume_gps"):
            load_emulator(write(d))
        volume[field] = kept
    kept = volume["gp"]                   # the GPs' inputs without the shape
    volume["gp"] = {**kept, "gps": [{**g, "x": [row[:-3] for row in g["x"]],
                                     "lengths": g["lengths"][:-3]} for g in kept["gps"]]}
    with pytest.raises(SurrogateFileError, match="volume_gps"):
        load_emulator(write(d))
