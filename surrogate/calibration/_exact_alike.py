"""Explanations that make exactly the readings a selection makes, whatever the data.

Some pairs of the catalogue are one and the same to every reading of bend and gauge, by
the physics rather than by a fit: a gauge reading k x the chamber pressure and a batch of
specimens uniformly k x as stiff (both layers' Ogden mu x k take the same shape at the
same injected volume at k x the pressure). An effect says so in ``Effect.exactly_as``.
No data set can choose between them, so the selection names the catalogue's first only
because it is one parameter; the report lists the other beside it (``indistinguishable``,
``exact``: true) with its sizes and the measurements that tell them apart, whether or not
the loop fitted it as a candidate (with three curves a two-parameter pair is not).
"""

from __future__ import annotations

from surrogate.calibration.effects import EFFECTS


def exact_alikes(chosen: tuple[str, ...], params: dict[str, dict], rmse_cv_deg: float | None,
                 rmse_cv_pressure_pa: float | None) -> list[dict]:
    """The ``indistinguishable`` entries that replace a member of ``chosen`` by the
    effects it is exactly (``params``: the selection's {name: {value, sd, unit, effect}});
    the selection's cross-validated errors are theirs too (the same readings)."""
    out = []
    for eid in chosen:
        e = EFFECTS[eid]
        if not e.exactly_as:
            continue
        own = {n: p for n, p in params.items() if p.get("effect") == eid}
        effects = [x for x in chosen if x != eid] + [x for x in e.exactly_as if x not in chosen]
        out.append({"effects": effects, "rmse_cv_deg": rmse_cv_deg,
                    "rmse_cv_pressure_pa": rmse_cv_pressure_pa, "paired_z": 0.0,
                    "delta_bic_vs_selected": 0.0, "backed": True, "exact": True,
                    "why": e.exactly_as_why,
                    "params": e.exactly_as_params(own),
                    "measure": [e.measure_directly] + [EFFECTS[x].measure_directly
                                                       for x in e.exactly_as]})
    return out


def sentence(chosen: list[str], alike: list[dict]) -> str | None:
    """What the interpretation says of the exact alikes (None without any)."""
    exact = [a for a in alike if a.get("exact")]
    if not exact:
        return None
    words = []
    for a in exact:
        sizes = ", ".join(f"{n} = {p['value']:.3g} +/- {p['sd']:.2g}"
                          for n, p in a["params"].items())
        words.append(f"{' and '.join(chosen)} makes the same readings exactly as "
                     f"{' and '.join(a['effects'])} ({sizes}): {a['why']}, so no reading of "
                     f"bend or gauge tells them apart and {' and '.join(chosen)} is named "
                     "only as the fewer parameters. To tell them apart: "
                     + "; ".join(a["measure"]) + ".")
    return " ".join(words)
