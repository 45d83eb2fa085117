"""The volume nodes and the top pressure nodes read with the pressure curve's shape among
their GPs' inputs (``surrogate.emulator.shape_gps``): the leave-one-out means they are
fitted on, the fitted designs reproduced, one query against a batch, and the emulator
file's fields."""

import json

import numpy as np
import pytest

from surrogate.emulator.curve_gps import CurveGPs, anchor_index, rise_outputs
from surrogate.emulator.features import ANGLE_NODES_DEG
from surrogate.emulator.gp import from_hyperparameters
from surrogate.emulator.shape_gps import (
    TOP_PRESSURE_FROM,
    TOP_SHAPE_NODES_DEG,
    VOLUME_SHAPE_NODES_DEG,
    fit_shape_gps,
    loo_pressure_means,
    pressure_shape,
    shape_gps_from_dict,
    shape_scaling,
)
from surrogate.emulator.vector_gp import MEANS_ONLY, fit_output_gps

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


def _curve_gps(u: np.ndarray, y: np.ndarray) -> CurveGPs:
    """Curve GPs as ``build.fit_curve_gps`` fits them (without early-ended rows)."""
    a = anchor_index()
    z = rise_outputs(y, a)
    gp = fit_output_gps(u, z, shared=slice(0, N))
    volume = fit_shape_gps(u, z[:, N:], gp, VOLUME_SHAPE_NODES_DEG, shared=False)
    top = fit_shape_gps(u, z[:, TOP_PRESSURE_FROM:N], gp, TOP_SHAPE_NODES_DEG, shared=True)
    return CurveGPs(gp, a, None, volume, top)


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
    volume and top pressure GPs were fitted on, so they give back its own outputs; the
    correction fades away from the designs."""
    u, y = _rows(40, seed=6)
    cg = _curve_gps(u, y)
    gp, volume = cg.gp, cg.volume
    np.testing.assert_allclose(cg.predict_many(u, variance_of=MEANS_ONLY)[0], y, atol=2e-3)
    x = volume.gp.gps[0].x
    p_mean = gp.predict_many(u, variance_of=MEANS_ONLY)[0][:, :N]
    np.testing.assert_allclose(volume.inputs(u, p_mean), x, atol=1e-4)
    np.testing.assert_allclose(cg.top_pressure.inputs(u, p_mean),
                               cg.top_pressure.gp.gps[0].x, atol=1e-4)
    # uncorrected, the fitted designs' shape inputs are not the ones fitted on
    scaled = (pressure_shape(p_mean) - volume.shape_low) / volume.shape_span
    assert np.abs(scaled - x[:, 3:]).max() > 1e-3
    far = np.full((1, 3), 5.0)             # far outside the unit cube: no correction left
    p_far = gp.predict_many(far, variance_of=MEANS_ONLY)[0][:, :N]
    np.testing.assert_allclose(volume.inputs(far, p_far)[0, 3:],
                               ((pressure_shape(p_far) - volume.shape_low)
                                / volume.shape_span)[0], atol=1e-9)


def test_one_query_and_a_batch_agree_and_the_variance_is_the_shape_gps():
    a = anchor_index()
    u, y = _rows(40, seed=4)
    cg = _curve_gps(u, y)
    gp, volume, top_gps = cg.gp, cg.volume, cg.top_pressure
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
    # (atol: variances of ~1e-28 here are round-off of an exact interpolation, and two
    # summation orders of the same product differ in their sixth digit)
    np.testing.assert_allclose(var[:, N + a], v_var[:, a], rtol=1e-6, atol=1e-24)
    # the pressure nodes from 45 deg are the top GPs' (means and variances), below the
    # curve GPs' own
    t_mean, t_var = top_gps.predict_many(q, p_mean)
    np.testing.assert_allclose(mean[:, TOP_PRESSURE_FROM:N], t_mean, rtol=1e-12)
    np.testing.assert_allclose(var[:, TOP_PRESSURE_FROM:N], t_var, rtol=1e-6)
    np.testing.assert_allclose(mean[:, :TOP_PRESSURE_FROM], p_mean[:, :TOP_PRESSURE_FROM],
                               rtol=1e-12)
    m3, v3 = cg.predict(q[1], variance_of=np.array([3, TOP_PRESSURE_FROM + 2]))
    np.testing.assert_allclose(v3[[3, TOP_PRESSURE_FROM + 2]],
                               var[1, [3, TOP_PRESSURE_FROM + 2]], rtol=1e-4)
    assert np.isnan(np.delete(v3, [3, TOP_PRESSURE_FROM + 2])).all()
    # asking only the top volume nodes' variance gives theirs (the anchor read for them),
    # NaN else
    top = np.arange(N + a + 1, 2 * N)
    m2, v2 = cg.predict(q[0], variance_of=top)
    np.testing.assert_allclose(v2[top], var[0, top], rtol=1e-4)
    assert np.isnan(np.delete(v2, top)).all()
    assert cg.kernels(slice(0, TOP_PRESSURE_FROM)) == 1
    assert cg.kernels(slice(0, N)) == 2             # the top pressure nodes' one kernel
    assert cg.kernels(slice(N, 2 * N)) == volume.gp.kernels(slice(None)) >= 2
    assert pressure_shape(p_mean).shape == (6, 3)


def test_damaged_stored_shape_gps_are_refused_by_field():
    good = {"shape_low": [0.0, 0.1, 0.2], "shape_span": [1.0, 1.0, 1.0],
            "pressure_lengths": [0.5] * 7, "shape_alpha": [[0.0, 0.1, 0.2]] * 4}
    nodes, *arrays = shape_scaling(good, "volume_gps", VOLUME_SHAPE_NODES_DEG)
    assert nodes == VOLUME_SHAPE_NODES_DEG          # format 13 stored no shape nodes
    assert [a.shape for a in arrays] == [(3,), (3,), (7,), (4, 3)]
    for nodes in ([10.0, 5.0, 30.0, 40.0], [7.0, 30.0, 60.0, 90.0], [30.0], "abc"):
        with pytest.raises(ValueError, match="top_pressure_gps: shape_nodes_deg"):
            shape_scaling({**good, "shape_nodes_deg": nodes}, "top_pressure_gps",
                          TOP_SHAPE_NODES_DEG)
    # two shape numbers stored for three nodes' worth of shape
    with pytest.raises(ValueError, match="top_pressure_gps: shape_low"):
        shape_scaling({**good, "shape_nodes_deg": [5.0, 15.0, 30.0]}, "top_pressure_gps",
                      TOP_SHAPE_NODES_DEG)
    for field, value in (("shape_low", [0.0, 1.0]), ("shape_span", [1.0, 0.0, 1.0]),
                         ("shape_span", [1.0, float("inf"), 1.0]),
                         ("pressure_lengths", [-1.0] * 7), ("pressure_lengths", 1.0),
                         ("shape_alpha", [0.0, 0.0, 0.0]), ("shape_alpha", [[0.0, 0.0]]),
                         ("shape_alpha", [[0.0, float("nan"), 0.0]]), ("shape_low", None),
                         ("shape_low", "abc")):
        with pytest.raises(ValueError, match="volume_gps"):
            shape_scaling({**good, field: value}, "volume_gps", VOLUME_SHAPE_NODES_DEG)


def test_the_emulator_file_keeps_the_shape_gps_and_refuses_them_damaged(tmp_path):
    from surrogate.emulator import load_emulator
    from surrogate.emulator.file import FORMAT_VERSION, emulator_from_dict, emulator_to_dict
    from surrogate.errors import SurrogateFileError
    from surrogate.file_seal import KEY

    e = load_emulator("service/data/emulator.json")
    assert FORMAT_VERSION >= 14
    assert all(pe.curves.volume is not None and pe.curves.top_pressure is not None
               for pe in e.pairs.values())
    # two kernels among the pressure nodes: every node's variance still exact
    assert e.report["variance_nodes"]["shared_kernel"]
    np.testing.assert_array_equal(e.variance_nodes, np.arange(N))
    # the pair of the fewest designs: each load below builds its GPs (0.4 s against 0.9 s
    # for the largest; every pair is read by the same code)
    pe = min(e.pairs.values(), key=lambda p: len(p.coordinates))
    # the stored form gives back the same answers (the whole file's round trip:
    # test_emulator_balance.py; this one builds one pair's shape GPs, not every GP)
    u = pe.coordinates[:3] + 0.01
    p_mean = pe.curves.gp.predict_many(u, variance_of=MEANS_ONLY)[0][:, :N]
    for name, shape, nodes in (("volume_gps", pe.curves.volume, VOLUME_SHAPE_NODES_DEG),
                               ("top_pressure_gps", pe.curves.top_pressure,
                                TOP_SHAPE_NODES_DEG)):
        back = shape_gps_from_dict(json.loads(json.dumps(shape.as_dict())), name, nodes)
        assert back.shape_nodes_deg == nodes
        for a, b in zip(back.predict_many(u, p_mean), shape.predict_many(u, p_mean),
                        strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-12)

    def load(d: dict):
        """The file loader's validation, on the dict in memory (unsealed: read without a
        checksum); writing and reading 30 MB per variant cost ~10 s each."""
        return emulator_from_dict(d, "other.json")

    d = emulator_to_dict(e)               # one copy, each change undone after its load
    d.pop(KEY, None)
    # the first pair alone (each pair reads alike; building every pair's GPs is ~7 s a load)
    d["pairs"] = [p for p in d["pairs"] if p["pair"] == pe.pair]
    design = pe.coordinates[0]
    m_new = e.pairs[pe.pair].curves.predict(design, variance_of=MEANS_ONLY)[0]
    # a format-13 file has no top pressure GPs, a format-12 file no volume GPs either:
    # those nodes are the curve GPs' own, the rest unchanged
    stored = {name: [p.pop(name) for p in d["pairs"]]
              for name in ("top_pressure_gps", "volume_gps")}
    d["format_version"] = 12
    old12 = load(d)
    d["format_version"] = 13
    for p, v in zip(d["pairs"], stored["volume_gps"], strict=True):
        p["volume_gps"] = v
    old13 = load(d)
    d["format_version"] = FORMAT_VERSION
    for p, v in zip(d["pairs"], stored["top_pressure_gps"], strict=True):
        p["top_pressure_gps"] = v
    assert all(p.curves.volume is None and p.curves.top_pressure is None
               for p in old12.pairs.values())
    assert all(p.curves.volume is not None and p.curves.top_pressure is None
               for p in old13.pairs.values())
    m12 = old12.pairs[pe.pair].curves.predict(design, variance_of=MEANS_ONLY)[0]
    m13 = old13.pairs[pe.pair].curves.predict(design, variance_of=MEANS_ONLY)[0]
    low = slice(0, TOP_PRESSURE_FROM)
    np.testing.assert_allclose(m12[low], m_new[low], rtol=1e-9)    # the same pressure GPs
    np.testing.assert_allclose(m13[:N], m12[:N], rtol=1e-9)
    np.testing.assert_allclose(m13[N:], m_new[N:], rtol=1e-9)       # the same volume GPs

    for name in ("volume_gps", "top_pressure_gps"):
        shape = d["pairs"][0][name]
        damage = [("shape_span", [1.0, -1.0, 1.0]), ("gp", "x"), ("pressure_lengths", [1.0]),
                  ("shape_alpha", "x"), ("shape_nodes_deg", [90.0, 60.0, 30.0, 10.0])]
        for field, value in damage:
            kept, shape[field] = shape[field], value
            with pytest.raises(SurrogateFileError, match=name):
                load(d)
            shape[field] = kept
        kept = shape["gp"]                # the GPs' inputs without the shape
        shape["gp"] = {**kept, "gps": [{**g, "x": [row[:-3] for row in g["x"]],
                                        "lengths": g["lengths"][:-3]} for g in kept["gps"]]}
        with pytest.raises(SurrogateFileError, match=name):
            load(d)
        shape["gp"] = kept
    # top pressure GPs without volume GPs: refused (a file no fit writes)
    kept = d["pairs"][0].pop("volume_gps")
    with pytest.raises(SurrogateFileError, match="top_pressure_gps needs volume_gps"):
        load(d)
    d["pairs"][0]["volume_gps"] = kept


def test_the_early_ended_blend_at_weight_1_gives_the_conditioned_pressure_nodes():
    """The blend's shift of the pressure nodes is the conditioned means minus the answer's
    own (the top pressure GPs' from 45 deg), so a design blended at weight 1 answers the
    conditioned pressure nodes (an early-ended database curve is reproduced); the volume
    nodes keep the curve GPs' shift (conditioned minus their own volume means)."""
    from surrogate.emulator.early_ended_nodes import EarlyEndedRows

    u, y = _rows(40, seed=8)
    cg = _curve_gps(u, y)
    ue, ye = _rows(6, seed=9)
    ze = rise_outputs(ye, cg.volume_rise_anchor)
    ze[:, 25:N] = np.nan                 # ended short of 60 deg: pressure and volume
    ze[:, N + 25:] = np.nan
    blended = CurveGPs(cg.gp, cg.volume_rise_anchor, EarlyEndedRows(ue, ze), cg.volume,
                       cg.top_pressure)
    q = np.random.default_rng(10).random((4, 3))
    cond = blended._conditioned.predict_many(q)
    own = cg.gp.predict_many(q, variance_of=MEANS_ONLY)[0]
    base = cg.predict_many(q, variance_of=MEANS_ONLY)[0]
    w = np.array([1.0, 0.5, 0.0, 1.0])
    mean = blended.predict_many(q, variance_of=MEANS_ONLY, early_weight=w)[0]
    np.testing.assert_allclose(mean[w == 1, :N], cond[w == 1, :N], atol=1e-10)
    np.testing.assert_allclose(mean[1, :N], 0.5 * (base[1, :N] + cond[1, :N]), atol=1e-10)
    np.testing.assert_array_equal(mean[2], base[2])
    # the top pressure GPs' own means differ from the curve GPs' there: the case is live
    assert np.abs(base[:, TOP_PRESSURE_FROM:N] - own[:, TOP_PRESSURE_FROM:N]).max() > 1e-4
    # one query and a batch agree on the blend
    single = blended.predict(q[0], variance_of=MEANS_ONLY, early_weight=1.0)[0]
    np.testing.assert_allclose(single, mean[0], atol=1e-10)


def test_a_query_reads_the_shape_correction_off_the_pressure_kernel_row_only_when_shared():
    """One query's shape correction is the pressure GPs' kernel row times the shape GPs'
    weights (no kernel of its own) when the shape GPs were fitted on the same designs
    with the pressure nodes' kernel; with other length scales or other designs the shape
    GPs compute their own row, and either way the inputs are the same."""
    from dataclasses import replace

    u, y = _rows(40, seed=4)
    cg = _curve_gps(u, y)
    assert cg._shares_row
    q = np.random.default_rng(8).random(3)
    pressure = cg._pressure_gp
    log_p = pressure.predict(q, MEANS_ONLY)[0]
    rows = pressure.kernel_rows(q)
    for shape in (cg.volume, cg.top_pressure):
        np.testing.assert_allclose(shape.inputs(q, log_p, rows), shape.inputs(q, log_p),
                                   rtol=1e-10, atol=1e-12)
    other_lengths = replace(cg.volume, pressure_lengths=cg.volume.pressure_lengths * 1.1)
    assert not CurveGPs(cg.gp, cg.volume_rise_anchor, None, other_lengths,
                        cg.top_pressure)._shares_row
    u2, y2 = _rows(40, seed=6)
    other_designs = _curve_gps(u2, y2)
    assert not CurveGPs(cg.gp, cg.volume_rise_anchor, None, cg.volume,
                        other_designs.top_pressure)._shares_row
