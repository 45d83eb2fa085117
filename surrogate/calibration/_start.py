"""Starting (nominal) parameters per family: the model as it is.

``starting_parameters(families, model)``: ``model`` is None or "paper" (the paper's
constants, which describe the standard family), or a surrogate with
``family_parameters(design)`` (issue 5's API). A family the surrogate does not cover
starts from the paper's constants, with a warning in the report.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from surrogate.calibration._baseline import PAPER_PARAMETERS

STANDARD_FAMILY = ("pdms_1_10", "ecoflex_00_30", 1.0, 1.8, 0.15)


def _paper_row() -> list[float]:
    p = PAPER_PARAMETERS
    return [p.a_deg_per_mm, p.a_t_pa, p.b_t_per_mm, p.c]


def starting_parameters(families: tuple[tuple, ...], model: Any = None
                        ) -> tuple[np.ndarray, dict[str, Any]]:
    """(n_families, 4) array of (a, a_t, b_t, c) and a description of the model used."""
    rows, warnings = [], []
    if model is None or model == "paper":
        for fam in families:
            rows.append(_paper_row())
            if tuple(fam) != STANDARD_FAMILY:
                warnings.append(f"family {fam} is not the paper's standard family; its "
                                "starting parameters are the paper's constants anyway")
        return np.array(rows, float), {"name": "paper", "warnings": warnings,
                                       "source": "paper constants a = 0.101 deg/mm, "
                                       "a_t = 731.2 Pa, b_t = 7.179 /mm (log10)"}
    from solver.design import Design
    from solver.materials import get_material

    for fam in families:
        design = Design(body_material=get_material(fam[0]),
                        membrane_material=get_material(fam[1]), T_mm=fam[2], b_mm=fam[3],
                        h_mm=fam[4])
        try:
            p = model.family_parameters(design)
        except Exception as exc:  # noqa: BLE001 - e.g. OutOfFamilyError
            rows.append(_paper_row())
            warnings.append(f"family {fam}: {exc}; starting from the paper's constants")
            continue
        form = str(p.get("tau_form", p.get("tau", "log10")))
        if "log10" not in form and "ln" in form:
            warnings.append(f"family {fam}: tau form {form!r} read as log10")
        rows.append([float(p["a_deg_per_mm"]), float(p["a_t_pa"]), float(p["b_t_per_mm"]),
                     float(p.get("c", 0.0) or 0.0)])
    name = getattr(model, "name", "surrogate")
    return np.array(rows, float), {"name": name, "warnings": warnings,
                                   "provenance": dict(getattr(model, "provenance", {}) or {})}
