"""The force GPs node by node (surrogate/emulator/force_gps.py), on the shipped emulator
fitted from the database's blocked-tip FE curves."""

from __future__ import annotations

import numpy as np
import pytest

from service.settings import DATA_DIR
from surrogate.emulator import load_emulator
from surrogate.emulator.force_gps import ForceGPs, fit_force_nodewise


@pytest.fixture(scope="module")
def emulator():
    return load_emulator(DATA_DIR / "emulator.json")


def test_a_query_reads_every_segment_as_its_own_gp_would(emulator):
    """The batched query (one kernel row, stacked segments) gives each segment's own
    VectorGP answer, mean and variance, at random designs of the box."""
    u = np.random.default_rng(7).random((25, 6))
    for pe in emulator.pairs.values():
        assert isinstance(pe.force, ForceGPs)
        for row in u:
            mean, var = pe.force.predict(row)
            parts = [s.predict(row) for s in pe.force.segments]
            np.testing.assert_allclose(mean, np.concatenate([m for m, _ in parts]),
                                       rtol=1e-10, atol=1e-12)
            np.testing.assert_allclose(var, np.concatenate([v for _, v in parts]),
                                       rtol=1e-6, atol=1e-14)
        m_many, v_many = pe.force.predict_many(u)
        np.testing.assert_allclose(m_many[3], pe.force.predict(u[3])[0], rtol=1e-9)


def test_each_node_is_conditioned_on_every_design_that_reaches_it(emulator):
    """Nested training sets, largest at the first node (the fit report's counts), and a
    design that ends before the last node is in the GPs of the nodes it reaches: its own
    value is reproduced there (the nugget aside), not extrapolated from the others."""
    for key, pe in emulator.pairs.items():
        counts = [len(g.y) for g in pe.force.gps]
        assert counts == emulator.report["pairs"][key]["force_designs_by_node"]
        assert all(a >= b for a, b in zip(counts, counts[1:], strict=False))
        assert counts[0] > counts[-1]             # some designs end before the last node
    pe = emulator.pairs["pdms/ecoflex_00_30+"]
    last, first = pe.force.segments[-1].gps[0], pe.force.segments[0].gps[0]
    short = [x for x in first.x if not (np.abs(last.x - x).sum(axis=1) < 1e-12).any()]
    assert len(short) >= 20
    seg = pe.force.segments[0]
    for x in short[:5]:
        i = int(np.argmin(np.abs(first.x - x).sum(axis=1)))
        own = seg.center + seg.scale * np.array([g.y[i] for g in seg.gps])
        np.testing.assert_allclose(seg.predict(x)[0], own, atol=0.05 * np.abs(own).max())


def test_too_few_designs_reaching_every_node_is_refused():
    u = np.random.default_rng(0).random((6, 6))
    y = np.ones((6, 3))
    y[1:, 2] = np.nan
    with pytest.raises(ValueError, match="fewer than 2 designs reach every force node"):
        fit_force_nodewise(u, y)


def test_damaged_force_segments_are_refused_naming_the_file(emulator):
    """No segments, or a later segment trained on a design the first lacks (every later
    training set is a subset of the first): SurrogateFileError, not a wrong answer."""
    from surrogate.emulator.file import emulator_from_dict, emulator_to_dict
    from surrogate.errors import SurrogateFileError
    from surrogate.file_seal import KEY

    key = "pdms/ecoflex_00_30+"
    d = emulator_to_dict(emulator)
    d.pop(KEY, None)
    d["pairs"] = [p for p in d["pairs"] if p["pair"] == key]
    force = d["pairs"][0]["force"]
    assert emulator_from_dict(d, "ok.json").pairs[key].force is not None
    for damaged in ({"segments": []},
                    {"segments": [force["segments"][0], {
                        **force["segments"][1],
                        "gps": [{**g, "x": [[v + 0.5 for v in row] for row in g["x"]]}
                                for g in force["segments"][1]["gps"]]}]}):
        d["pairs"][0]["force"] = damaged
        with pytest.raises(SurrogateFileError, match="damaged emulator file"):
            emulator_from_dict(d, "other.json")
    d["pairs"][0]["force"] = force
