"""Schemas -> domain objects, with errors located in the request."""

from __future__ import annotations

import json
import math
from functools import lru_cache
from pathlib import PurePath
from typing import Any

from service.errors import FieldError, located
from service.schemas import DesignIn, SolveSettingsIn
from service.schemas.predict import Validity
from solver.design import LIMITS_MM, Design, design_from_dict
from solver.design_space import REUSED_ID_ALLOWED, reused_id
from solver.errors import InputError
from solver.settings import SolverSettings, settings_from_dict
from surrogate.json_plain import plain_json as jsonable  # one JSON-plain copy
from surrogate.predictor import normal_or_zero

# a design's own field names (a model's refusal: outside the box, out of family) -> their
# place in a request body that holds the design under "design"
DESIGN_LOCS: dict[str, tuple[str | int, ...]] = {
    name: ("design", name) for name in (*LIMITS_MM, "body_material", "membrane_material")}


def to_design(design: DesignIn | dict[str, Any], loc: tuple[str, ...] = ("body", "design")
              ) -> Design:
    text = (design.model_dump_json(exclude_none=True) if isinstance(design, DesignIn)
            else json.dumps(design, sort_keys=True))
    try:
        resolved = _design_from_json(text)
    except InputError as exc:   # the design itself: POST /v1/solve refuses it the same way
        refused = located(exc, loc)
        refused.design_refused = True
        raise refused from None
    for role in ("body_material", "membrane_material"):
        material = getattr(resolved, role)
        what = reused_id(material)      # one id, one set of parameters
        if what is not None:
            raise FieldError((*loc, role, "id"), f"inline material reuses the {what} "
                             f"{material.id!r} with other parameters", REUSED_ID_ALLOWED,
                             design_refused=True)
    return resolved


@lru_cache(maxsize=4096)
def _design_from_json(text: str) -> Design:
    """Designs repeat across requests: validate each distinct one once (Design is frozen)."""
    return design_from_dict(json.loads(text))


@lru_cache(maxsize=4096)
def design_dict(design: Design) -> dict[str, Any]:
    """``design.as_dict()``, cached (treat the result as read-only)."""
    return design.as_dict()


def to_settings(settings: SolveSettingsIn, loc: tuple[str, ...] = ("body", "settings")
                ) -> SolverSettings:
    try:
        return settings_from_dict(settings.model_dump(exclude_unset=True))
    except InputError as exc:
        raise located(exc, loc) from None


def finite_list(values: Any) -> list[float | None]:
    """Floats for an answer (HTTP and CLI alike): NaN and infinity become null, a subnormal
    magnitude and -0.0 become 0.0 (``normal_or_zero``)."""
    return [v if math.isfinite(v) else None
            for v in normal_or_zero(values).ravel().tolist()]


# the validity fields a Prediction may carry beyond in_domain, flags and messages: the
# HTTP schema's (one table: a field added there reaches the CLI and HTTP alike)
VALIDITY_FIELDS = tuple(n for n in Validity.model_fields
                        if n not in ("in_domain", "flags", "messages"))


def prediction_body(prediction: Any, model: str, level: float | None = None,
                    design: Design | None = None) -> dict[str, Any]:
    """The one plain-data form of a ``surrogate.predictor.Prediction``, for HTTP and the CLI:
    angles (deg) with the band, force (mN, blocked tip) and injected volume (ul) when the
    model has them, validity and provenance. NaN (past the FE's range) becomes null.
    ``in_domain`` says whether the design is in the model's domain, for every model
    alike: flags about asked points never make it false (``design_in_domain``)."""
    from surrogate.predictor import design_in_domain

    validity = dict(prediction.validity or {})

    def opt(values: Any) -> list[float | None] | None:
        return None if values is None else finite_list(values)

    return {"model": model, "level": getattr(prediction, "level", level),
            "design": design_dict(getattr(prediction, "design", None) or design),
            "pressure_pa": finite_list(prediction.pressure_pa),
            "angle_deg": finite_list(prediction.angle_deg),
            "lower_deg": finite_list(prediction.lower_deg),
            "upper_deg": finite_list(prediction.upper_deg),
            "force_mn": opt(getattr(prediction, "force_mn", None)),
            "force_lower_mn": opt(getattr(prediction, "force_lower_mn", None)),
            "force_upper_mn": opt(getattr(prediction, "force_upper_mn", None)),
            "volume_ul": opt(getattr(prediction, "volume_ul", None)),
            "validity": jsonable({
                "in_domain": design_in_domain(validity),
                "flags": [str(f) for f in validity.get("flags", [])],
                "messages": [str(m) for m in validity.get("messages", [])],
                **{k: validity[k] for k in VALIDITY_FIELDS if k in validity}}),
            "form": getattr(prediction, "form", None),
            "provenance": public_provenance(dict(prediction.provenance or {}))}


def public_provenance(provenance: dict[str, Any]) -> dict[str, Any]:
    """Provenance for an answer: a ``*_path`` entry (where a file was on the machine that
    made the model) becomes the file's logical name under the key without ``_path``
    (``database_path: /home/x/curves.h5`` -> ``database: curves.h5``)."""
    out: dict[str, Any] = {}
    for key, value in provenance.items():
        if key.endswith("_path"):
            out[key.removesuffix("_path")] = PurePath(str(value)).name if value else value
        else:
            out[key] = value
    return jsonable(out)
