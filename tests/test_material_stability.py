"""The Ogden stability check's shortcut (solver.ogden_paths.terms_each_stable): a
material whose every term is stable on its own is stable, without walking the paths;
the walk still refuses the rest."""

from __future__ import annotations

import numpy as np
import pytest

from solver.design_space import PAIRS, scaled_material
from solver.errors import InputError
from solver.materials import MATERIALS, make_material
from solver.ogden_paths import terms_each_stable, unstable_at, unstable_on_paths


def test_a_single_term_is_stable_on_every_path_where_the_shortcut_says_so():
    alphas = np.concatenate((np.linspace(1.0, 40.0, 300), np.linspace(-40.0, -2.0, 300)))
    for a in alphas:
        mu = float(np.sign(a))
        assert terms_each_stable([mu], [a])
        assert unstable_on_paths([mu], [a]) is None, a


def test_sums_of_stable_terms_are_stable_on_every_path():
    rng = np.random.default_rng(7)
    for _ in range(400):
        n = int(rng.integers(1, 4))
        alpha = rng.uniform(1.0, 25.0, n) * rng.choice([-1.0, 1.0], n)
        alpha[alpha < 0] -= 1.0                      # negative ones at -2 or below
        mu = rng.lognormal(0.0, 2.0, n) * np.sign(alpha)
        assert terms_each_stable(mu, alpha)
        assert unstable_on_paths(mu, alpha) is None, (mu, alpha)


@pytest.mark.parametrize("alpha", [0.3, 0.5, 0.9, -0.4, -1.5])
def test_a_term_outside_the_shortcut_is_walked_and_an_unstable_one_refused(alpha):
    mu = float(np.sign(alpha))
    assert not terms_each_stable([mu], [alpha])
    found = unstable_on_paths([mu], [alpha])
    assert found is not None and unstable_at([mu], [alpha]) == found
    with pytest.raises(InputError) as e:
        make_material("soft", [mu], [alpha])
    assert e.value.field == "mu_kpa" and "alpha >= 1 or alpha <= -2" in e.value.allowed


def test_the_presets_and_their_scaled_copies_take_the_shortcut():
    for body, membrane in PAIRS:
        for preset in (body, membrane):
            m = MATERIALS[preset]
            assert terms_each_stable(m.mu_kpa, m.alpha), preset
            s = scaled_material(preset, 1.7)
            assert terms_each_stable(s.mu_kpa, s.alpha)


def test_nearly_cancelling_terms_are_still_refused():
    with pytest.raises(InputError) as e:
        make_material("cancel", [10.0, -5.0], [2.0, 3.99])
    assert e.value.field == "mu_kpa" and "falls with stretch" in e.value.detail
