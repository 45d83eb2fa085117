"""POST /v1/calibrate (measured rows -> calibration report) and GET /v1/effects (catalogue).

The report is the one ``balloon calibrate`` writes (docs/calibration.md). Saving the
augmented model (``save``) changes server state, so it needs the API key.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Annotated, Any

from fastapi import APIRouter, Request, Security
from pydantic import BaseModel, ConfigDict, Field, PlainValidator, WithJsonSchema

from service.commands.calibrate import FOLDS
from service.deps import API_KEY_HEADER, ModelsDep, SettingsDep, require_api_key
from service.disconnect import unless_disconnected
from service.errors import (
    FIELD_FORMS,
    FIELD_RANGES,
    ConflictError,
    FieldError,
    UnavailableError,
    located,
)
from service.models import check_new_model_name, name_rule
from service.schemas import Schema
from service.schemas._ranges import field_ranges
from service.schemas.common import MATERIAL_ID
from solver.errors import ExistsError, InputError
from surrogate.measured_cell import CELL_WORDS, cell_problem

router = APIRouter(prefix="/v1", tags=["calibration"])

# Two replicate specimens of one design (the loop needs at least 2 curves).
EXAMPLE_ROWS = [
    {"curve_id": cid, "L_mm": 7.1, "t_mm": 0.5, "body_material": "pdms_1_10",
     "membrane_material": "ecoflex_00_30", "pressure_pa": p, "angle_deg": a,
     "time_s": float(i), "flow_ul_s": 2.5}
    for cid, points in (("s1", [(0, 0.1), (400, 1.6), (800, 4.8), (1200, 12.0), (1600, 30.5)]),
                        ("s2", [(0, -0.2), (400, 1.9), (800, 5.1), (1200, 12.6), (1600, 31.4)]))
    for i, (p, a) in enumerate(points)
]
# The same readings from a lab that logs the syringe pump's dispensed volume, not time
# (docs/measured-data.md, "A measured volume").
EXAMPLE_ROWS_BY_VOLUME = [
    {k: v for k, v in row.items() if k not in ("time_s", "flow_ul_s")}
    | {"volume_ul": 2.5 * row["time_s"]} for row in EXAMPLE_ROWS]


def _cell(value: Any) -> Any:
    """One value of a measured row (``surrogate.measured_cell``'s rule, a data file's too):
    named by its row and column in the 422 (a 400-digit integer, true, a list are input
    errors, not a 500)."""
    problem = cell_problem(value)
    if problem is not None:
        raise ValueError(problem)
    return value


Cell = Annotated[Any, PlainValidator(_cell),
                 WithJsonSchema({"type": ["number", "string", "null"]})]


class CalibrateRequest(Schema):
    """Measured rows (columns as in docs/measured-data.md) and the starting model."""

    rows: list[dict[str, Cell]] = Field(..., min_length=1, max_length=20_000,
                                       description="one object per observation",
                                       examples=[EXAMPLE_ROWS, EXAMPLE_ROWS_BY_VOLUME])
    model: str = Field("emulator", min_length=1, max_length=64, pattern=MATERIAL_ID,
                       description="baseline: emulator (nothing left open), exponential / "
                       "fitted, paper, or a saved model name")
    save: str | None = Field(None, min_length=1, max_length=64,
                             pattern=r"^[A-Za-z0-9][A-Za-z0-9_.\-]{0,63}$",
                             description="save the augmented model under this name "
                                         "(needs X-API-Key; a new name, not a built-in "
                                         "model's: emulator, exponential, fitted, paper)")
    folds: int = Field(5, ge=FOLDS[0], le=FOLDS[1], description="folds of the "
                       "cross-validation by curve (reduced to the number of curves when "
                       "there are fewer)")
    strict: bool = Field(False, description="refuse data that otherwise only get a warning "
                         "(pressures that look like kPa, duplicated rows)")




# its limits stated in every validation error, as the other requests' are
FIELD_RANGES.update(field_ranges([CalibrateRequest]))
FIELD_FORMS["save"] = "a new name of " + name_rule()
FIELD_RANGES["rows.*"] = ("an object: one observation, its columns named as in "
                          "docs/measured-data.md")
FIELD_RANGES["rows.*.*"] = CELL_WORDS


class Candidate(BaseModel):
    model_config = ConfigDict(extra="allow")
    effect: str = Field(description="effect id(s), + joined")
    rmse_cv_deg: float | None = Field(description="cross-validated RMS error, degrees")
    delta_bic: float | None = Field(description="BIC change against the baseline")
    params: dict[str, Any]
    plausible: bool | None


class CalibrationReport(BaseModel):
    """The calibration report; more fields than listed here are included."""

    model_config = ConfigDict(extra="allow")
    rmse_model_deg: float = Field(description="the starting model's RMS error, degrees")
    rmse_before_deg: float | None = Field(..., description="recalibrated baseline, cross-"
                                          "validated RMS error, degrees (null: not finite)")
    rmse_after_deg: float | None = Field(..., description="with the selected effects, cross-"
                                         "validated RMS error, degrees (null: not finite)")
    noise_floor_deg: float | None = Field(description="RMS measurement noise from "
                                          "replicates, degrees (null: no replicates)")
    selected_effects: list[str]
    candidates: list[Candidate]
    residual_structured_after: bool
    residual_within_baseline_band: bool = Field(
        False, description="what is left is more than replicate scatter but within the "
        "baseline's own band at the design: not structured, and not replicate scatter either "
        "(an FE solve of the design decides)")
    interpretation: str
    saveable: dict[str, Any] | None = Field(
        None, description="whether this calibration can be saved as a model (`ok`) and, "
        "if not, why (`why`): the same words a request with `save` would be refused with")
    left_out: dict[str, Any] | None = Field(
        None, description="the readings left out of the fit as past the end of the FE's "
        "range for their nominal design, predicted afterwards by the calibrated model: "
        "`readings`, `answered`, `rmse_deg` (degrees, over the answered), `why`; null when "
        "none were left out")
    predictions: list[dict[str, Any]] | None = Field(
        None, description="every reading the fit used: `curve_id`, `pressure_pa` (Pa), "
        "`angle_deg`, the recalibrated baseline's and the selected effects' fitted angle "
        "there (`angle_before_deg`, `angle_after_deg`, degrees) and, read against the "
        "injected volume, the fitted gauge pressure `pressure_after_pa` (Pa; null "
        "otherwise); then the readings left out as past the nominal design's FE range, "
        "`left_out` true, with the calibrated model's angle there")
    saved_model: str | None = None


class EffectList(BaseModel):
    items: list[dict[str, Any]]


@router.get("/effects", response_model=EffectList, summary="The catalogue of candidate effects")
def effects() -> EffectList:
    """Every effect the calibration tests: parameters with units, bounds, plausible range,
    the columns it needs, and how it acts on the model."""
    from surrogate.calibration import catalogue_dicts

    return EffectList(items=catalogue_dicts())


@router.post("/calibrate", response_model=CalibrationReport,
             summary="Find what the model misses in measured curves; error before and after")
async def calibrate(request: CalibrateRequest, models: ModelsDep, settings: SettingsDep,
                    http: Request,
                    key: Annotated[str | None, Security(API_KEY_HEADER)] = None
                    ) -> CalibrationReport:
    """The calibration runs in a worker thread and stops soon after its client
    disconnects (service.disconnect): nothing is saved then."""
    return await unless_disconnected(
        http, lambda cancel: _calibrate(request, models, settings, key, cancel))


def _calibrate(request: CalibrateRequest, models: Any, settings: Any, key: str | None,
               cancel: threading.Event) -> CalibrationReport:
    from surrogate.calibration import (
        DataError,
        jsonable,
        observations_from_rows,
        run_calibration,
        save_model,
    )

    if request.save is not None:
        require_api_key(settings, key)
        _check_save_name(request.save, settings.models_dir)  # before the work
    try:  # the data's errors: the loader's, then the loop's (e.g. fewer than 2 curves)
        obs = observations_from_rows(request.rows, strict=request.strict)
        _check_size(obs, settings)
        start = "paper" if request.model == "paper" else models.get(request.model)
        cal = run_calibration(obs, start, folds=request.folds, cancel=cancel)
    except DataError as exc:
        loc: tuple[str | int, ...] = ("body", "rows")
        if exc.row is not None:
            loc += (exc.row - 1,)
        raise FieldError(loc + (exc.column,), exc.detail, exc.allowed) from None
    report = jsonable(cal.report)
    report["model"]["name"] = request.model
    if request.save is not None:
        try:  # a reserved or already used name (atomic create: one of two saves wins),
              # or a calibration the saved formats cannot hold (save_model: saveable)
            check_new_model_name(request.save, settings.models_dir)
            save_model(cal, request.save, settings.models_dir)
        except ExistsError as exc:  # the name, or one differing from it only in case
            raise _conflict(exc, request.save) from None
        except InputError as exc:
            raise located(exc, ("body",), {"name": ("save",)}) from None
        report["saved_model"] = request.save
    return CalibrationReport(**report)


def _check_size(obs: Any, settings: Any) -> None:
    """422 at ``rows`` when the data hold more curves or nominal designs than this server
    calibrates in one request (``BALLOON_MAX_CALIBRATION_CURVES``, ``..._DESIGNS``): the
    loop's work grows with both, and 20,000 rows of 5,000 curves kept a worker busy past
    5 minutes. ``balloon calibrate`` on one's own machine has no such limit."""
    designs = {tuple(v for k, v in obs.curve_design(i).items()
                     if k not in ("curve_id", "flow_ul_s")) for i in range(obs.n_curves)}
    for count, limit, what, setting in (
            (obs.n_curves, settings.max_calibration_curves, "curves (distinct curve_id)",
             "BALLOON_MAX_CALIBRATION_CURVES"),
            (len(designs), settings.max_calibration_designs, "nominal designs (material "
             "pair, T_mm, b_mm, h_mm, L_mm, t_mm)", "BALLOON_MAX_CALIBRATION_DESIGNS")):
        if count > limit:
            raise FieldError(("body", "rows"), f"{count} {what}: more than this server "
                             f"calibrates in one request ({limit}, {setting})",
                             f"at most {limit} {what.split(' (')[0]} per request; "
                             "`balloon calibrate` runs any number on your machine")


def _conflict(exc: ExistsError, name: str) -> ConflictError:
    """409 for a taken name (or one differing from the new name only in case): its
    ``model`` member is the saved model's name (``Lab1`` asked beside a saved ``lab1``:
    lab1)."""
    return ConflictError(f"save: {getattr(exc, 'detail', exc)}; choose a new name",
                         model=getattr(exc, "name", None) or name)


def _check_save_name(name: str, models_dir: Path) -> None:
    """The name ``save`` asks for, checked before the calibration's work: not a built-in
    model's in any case (422 at ``save``), not taken, not a saved model's in another case
    (409). The save itself is an atomic create: of two concurrent saves one wins."""
    from surrogate.calibration._saved import _check_name

    if models_dir.exists() and not models_dir.is_dir():
        # the server's setting, not the request's: every name was "already exists" (409)
        raise UnavailableError("saving is unavailable: the server's models directory "
                               "(BALLOON_MODELS_DIR) is not a directory")
    try:
        _check_name(name)
        check_new_model_name(name, models_dir)
    except ExistsError as exc:
        raise _conflict(exc, name) from None
    except InputError as exc:
        raise located(exc, ("body",), {"name": ("save",)}) from None
    if (models_dir / f"{name}.json").exists():
        raise ConflictError(f"save: a model named {name!r} already exists; choose a new "
                            "name", model=name)
