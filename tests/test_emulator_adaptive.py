"""Adaptive refinement (surrogate/emulator/adaptive.py) on the shipped emulator: the next
designs are in the box, spaced apart, away from the database designs and from curves that
ended early, and the count is checked."""

from __future__ import annotations

import numpy as np
import pytest

from service.settings import DATA_DIR
from solver.design_space import locate
from solver.errors import InputError
from surrogate.emulator import load_emulator
from surrogate.emulator.adaptive import MIN_SPACING, next_designs
from surrogate.emulator.emulator import FAILED_RADIUS


@pytest.fixture(scope="module")
def emulator():
    return load_emulator(DATA_DIR / "emulator.json")


@pytest.fixture(scope="module")
def round_of_24(emulator):
    """One adaptive round of 24 designs (~20 s: every candidate's curve with its band),
    shared by the tests that check what a round proposes."""
    return next_designs(emulator, 24)


def test_next_designs_keep_away_from_known_and_from_early_ended_curves(emulator,
                                                                      round_of_24):
    points = round_of_24
    assert len(points) == 24
    assert len({p.key for p in points}) == 24
    by_group: dict[str, list[np.ndarray]] = {}
    for p in points:
        bp = locate(p.design, reduced=True)
        u = bp.coordinates()
        pes = [pe for key, pe in emulator.pairs.items() if key[:-1] == bp.group]
        for pe in pes:
            assert np.min(np.linalg.norm(pe.coordinates - u, axis=1)) >= MIN_SPACING
            for fu, _, _ in pe.failed:
                assert np.linalg.norm(np.asarray(fu) - u) >= FAILED_RADIUS
        for other in by_group.get(bp.group, []):
            assert np.linalg.norm(other - u) >= MIN_SPACING
        by_group.setdefault(bp.group, []).append(u)


def test_a_count_outside_its_range_is_refused_with_the_option_named(emulator):
    with pytest.raises(InputError, match="--adaptive"):
        next_designs(emulator, 0)


def test_no_design_whose_emulated_volume_reaches_the_fe_volume_stop(emulator, round_of_24):
    """A candidate whose FE curve would stop at the volume limit before 90 deg adds no
    curve to interpolate: none is proposed (reduced designs, length scale 1)."""
    from surrogate.emulator.emulator import N_NODES
    from surrogate.emulator.features import ANGLE_NODES_DEG

    for p in round_of_24:
        bp = locate(p.design, reduced=True)
        try:
            pe = emulator._pair(bp, bp.coordinates())
        except InputError:       # near the balance: no sign to check the volume of
            continue
        mean, _ = pe.curves.predict(bp.coordinates())
        volume_at_90_ul = ANGLE_NODES_DEG[-1] * np.exp(mean[2 * N_NODES - 1])
        assert volume_at_90_ul < pe.fe_max_volume_ul


def test_no_design_whose_fe_curve_is_emulated_to_end_early(emulator, round_of_24):
    """The group's range model (where its database curves ended) keeps the candidates
    whose FE curve would end before 85 deg out of an adaptive round."""
    assert round_of_24
    for p in round_of_24:
        bp = locate(p.design, reduced=True)
        models = [pe for key, pe in emulator.pairs.items() if key[:-1] == bp.group]
        for pe in models:
            if pe.range_model is not None:
                assert 90.0 * pe.range_model.predict(bp.coordinates())[0][0] >= 85.0


def test_the_score_is_the_angle_sd_on_the_worse_axis_by_hand():
    """Power-law curves p ~ theta^3 and V ~ theta^1.5: an sd s in log(x/theta) moves the
    angle at a given x by theta x s / (d log x / d log theta); the score takes the larger
    of the pressure's and the volume's."""
    from surrogate.emulator.adaptive import angle_sd_deg
    from surrogate.emulator.features import ANGLE_NODES_DEG

    log_theta = np.log(ANGLE_NODES_DEG)
    mean = np.concatenate((2.0 + (3.0 - 1.0) * log_theta, -1.0 + (1.5 - 1.0) * log_theta))
    n = len(ANGLE_NODES_DEG)
    sd = np.concatenate((np.full(n, 0.01), np.full(n, 0.01)))
    # pressure: theta 0.01 / 3; volume: theta 0.01 / 1.5 (the larger)
    np.testing.assert_allclose(angle_sd_deg(mean, sd), ANGLE_NODES_DEG * 0.01 / 1.5,
                               rtol=1e-9)
    sd[:n] = 0.1                 # now the pressure's: theta 0.1 / 3
    np.testing.assert_allclose(angle_sd_deg(mean, sd), ANGLE_NODES_DEG * 0.1 / 3.0,
                               rtol=1e-9)
    # past a pressure maximum (p falling with theta) the slope is floored, not negative
    mean[:n] = 2.0 - 1.5 * log_theta
    assert (angle_sd_deg(mean, sd) > 0).all()
