"""Which model answers a request: the ``model`` field of /v1/predict and /v1/inverse.

    "emulator"     the design-space emulator (the default), loaded once at start-up
                   from ``emulator_path``
    "exponential"  the paper's exponential form fitted to the same database (loaded from
                   ``surrogate_path``); "fitted" is its older name
    "paper"        the paper's published constants (``surrogate.paper_surrogate()``)
    any other      a saved calibrated model in ``models_dir``, loaded through
                   ``surrogate.calibration.load_model(name, models_dir)`` (the one hook)

Every one implements ``surrogate.predictor.Predictor``: callers never branch on kind.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from service.errors import FieldError, UnavailableError
from service.saved_model_file import saved_file_fault
from solver.errors import BalloonError, ExistsError, InputError, NotFoundError

# the built-in models by their current names, as errors list them ("fitted", the older
# name of "exponential", is still answered but never offered)
BUILT_IN_MODELS = ("emulator", "exponential", "paper")
BUILT_IN_WORDS = ", ".join(f'"{n}"' for n in BUILT_IN_MODELS)

log = logging.getLogger("balloon.service")


@dataclass
class ModelRegistry:
    """The loaded surrogate plus lazily built named ones. Opening the models directory
    removes the temporary files of saves a killed process left there (older than a
    minute: ``surrogate.calibration._saved.remove_stale_temporaries``)."""

    surrogate_path: Path
    models_dir: Path
    emulator_path: Path | None = None
    fitted: Any = None
    fitted_error: str | None = None
    fitted_sha256: str | None = None     # of the loaded file's bytes: which model answers
    emulator: Any = None
    emulator_error: str | None = None
    emulator_sha256: str | None = None
    _paper: Any = field(default=None, repr=False)

    def __post_init__(self) -> None:
        from surrogate.calibration._saved import remove_stale_temporaries

        removed = remove_stale_temporaries(self.models_dir)
        if removed:     # server-side only: the names, never to a client
            log.info("removed %d temporary file(s) of unfinished saves from the models "
                     "directory: %s", len(removed), ", ".join(removed))

    def load_fitted(self) -> None:
        """Load the emulator and the fitted exponential surrogate (at start-up); a failure
        is kept (reported by /v1/health and on use), not raised."""
        self.load_exponential()
        self._load_emulator()

    def load_exponential(self) -> None:
        """Load the fitted exponential surrogate alone (a command that asks it needs no
        emulator: `balloon predict --model exponential` had loaded both, 12 s and 667 MB
        against 2.7 s); a failure is kept, as ``load_fitted``."""
        try:
            from surrogate import load_surrogate

            self.fitted = load_surrogate(self.surrogate_path)
            self.fitted_error = None
            self.fitted_sha256 = _sha256(self.surrogate_path)
        except Exception as exc:  # noqa: BLE001 - reported by /v1/health and on use
            self.fitted = None
            path = Path(self.surrogate_path)  # clients see the file's name, not its place
            text = str(exc).replace(str(path), path.name)
            self.fitted_error = f"{type(exc).__name__}: {text}"

    def _load_emulator(self) -> None:
        if self.emulator_path is None:
            self.emulator_error = "no emulator file configured"
            return
        try:
            from surrogate.emulator import load_emulator

            self.emulator = load_emulator(self.emulator_path)
            self.emulator_error = None
            self.emulator_sha256 = _sha256(self.emulator_path)
            # each group's variance kernels made now, not in its first request (0.05-0.6 s)
            threading.Thread(target=_warm_up, args=(self.emulator,), daemon=True,
                             name="emulator-warm-up").start()
        except FileNotFoundError:
            self.emulator = None
            self.emulator_error = (f"emulator file {Path(self.emulator_path).name} does not "
                                   "exist (make one with `balloon fit --db DB -o FILE "
                                   "--emulator-output EMULATOR`)")
        except Exception as exc:  # noqa: BLE001 - reported by /v1/health and on use
            self.emulator = None
            path = Path(self.emulator_path)   # clients see the file's name, not its place
            text = _plain_error(exc).replace(str(path), path.name).replace(
                str(path.parent), "")
            self.emulator_error = f"{type(exc).__name__}: {text}"

    def get(self, name: str) -> Any:
        if name == "emulator":
            if self.emulator is None and self.emulator_error is None:
                self._load_emulator()      # an app built without start-up loading
            if self.emulator is None:
                raise UnavailableError(
                    f'model "emulator": the emulator is not loaded '
                    f"({self.emulator_error or 'no file'}); use "
                    'model "exponential" or "paper", or set BALLOON_EMULATOR_PATH and '
                    "restart")
            return self.emulator
        if name in ("fitted", "exponential"):
            if self.fitted is None and self.fitted_error is None:
                self.load_exponential()    # an app built without start-up loading
            if self.fitted is None:
                raise UnavailableError(
                    f'model "{name}": no fitted surrogate is loaded ({self.fitted_error}); '
                    'use model "paper", or set BALLOON_SURROGATE_PATH and restart')
            return self.fitted
        if name == "paper":
            if self._paper is None:
                try:
                    from surrogate import paper_surrogate
                except ImportError as exc:
                    raise UnavailableError(f"the paper model is not available ({exc})"
                                           ) from None
                self._paper = paper_surrogate()
            return self._paper
        return load_calibrated(name, self.models_dir, lambda: self.get("emulator"))


def _sha256(path: Path) -> str:
    """The SHA-256 of a model file just loaded (``surrogate.fit_provenance.file_sha256``,
    imported here: the registry's module is imported by every CLI command)."""
    from surrogate.fit_provenance import file_sha256

    return file_sha256(path)


def _plain_error(exc: BaseException) -> str:
    """An error's message without local directories (answers name files by their name)."""
    text = str(exc)
    return text.replace(str(Path.home()), "~")


def _warm_up(emulator: Any) -> None:
    """``Emulator.warm_up`` in the background; a failure there leaves the kernels to be
    made by the first queries (as without it) and is not the service's to report."""
    try:
        emulator.warm_up()
    except Exception:  # noqa: BLE001, S110 - the queries make what it could not
        pass


def load_calibrated(name: str, models_dir: Path, design_space: Any = None) -> Any:
    """A saved calibrated model by name: NotFoundError when there is none, 503 when its
    file is damaged. ``design_space`` gives the emulator a calibration against it answers
    through. The answers name the model only: never the models directory, never the other
    saved models (another user's)."""
    from surrogate.calibration import load_model
    from surrogate.calibration._saved import NAME_PATTERN

    fault = saved_file_fault(models_dir, name) if NAME_PATTERN.fullmatch(name) else None
    if fault is not None:
        raise UnavailableError(f"the saved model {name!r} cannot be read: its entry in the "
                               f"server's models directory is {fault}")
    try:
        return load_model(name, models_dir, design_space)
    except (NotFoundError, FileNotFoundError, IsADirectoryError):
        raise NotFoundError(f"no saved model {name!r}; known models are {BUILT_IN_WORDS} "
                            "and the saved ones, by name") from None
    except BalloonError as exc:  # SavedModelError: a damaged file on the server
        raise UnavailableError(str(exc)) from None
    except Exception as exc:  # noqa: BLE001 - unreadable file (permissions, I/O)
        raise UnavailableError(f"the saved model {name!r} cannot be read "
                               f"({type(exc).__name__})") from None


class CaseClashError(ExistsError, InputError):
    """A new saved model's name differs only in case from a saved model's: on a
    case-insensitive file system (macOS, Windows) both are one file, so the first would be
    answered for the second, or replaced by it (409 over HTTP, the CLI's one line)."""

    def __init__(self, name: str, existing: str) -> None:
        InputError.__init__(self, "name", f"a model named {existing!r} already exists and "
                            f"{name!r} differs from it only in case", "a new name")
        self.name = existing


def name_rule() -> str:
    """A new saved model's name, in words (the rule of surrogate.calibration's
    NAME_PATTERN and RESERVED, and this module's case rule)."""
    from surrogate.calibration._saved import RESERVED

    return ("1-64 letters, digits, '_', '.', '-', starting with a letter or digit, without "
            ".json (the file's ending is added); not " + ", ".join(RESERVED) + " in any case")


def check_new_model_name(name: str, models_dir: Path) -> None:
    """Refuse a name for a new saved model that does not have NAME_PATTERN's form (a
    final newline: "lab1\n" had made a file "lab1\n.json"), that is a built-in model's in
    another case ("Emulator", "PAPER": a user could not tell which one answers) or that
    differs only in case from a model saved in ``models_dir`` (CaseClashError). The rest
    of the rule (the exact built-in names, an existing file) is ``save_model``'s."""
    from surrogate.calibration._saved import NAME_PATTERN, RESERVED

    if not NAME_PATTERN.fullmatch(name) or name.lower().endswith(".json"):
        raise InputError("name", f"invalid model name {name!r}", name_rule())
    folded = name.casefold()
    if folded in RESERVED and name not in RESERVED:
        raise InputError("name", f"invalid model name {name!r}: the built-in model "
                         f"{folded!r} in another case", name_rule())
    if not models_dir.is_dir():
        return
    for path in models_dir.glob("*.json"):
        if path.stem != name and path.stem.casefold() == folded:
            raise CaseClashError(name, path.stem)


def require(model: Any, name: str, capability: str) -> Any:
    """``model`` if it has ``capability`` (a method or attribute), else a 422 naming the
    ``model`` field: a saved calibration against an exponential model predicts but does
    not invert; none searches designs."""
    if not hasattr(model, capability):
        what = CAPABILITY_WORDS.get(capability, "this request")
        raise FieldError(("body", "model"), f"model {name!r} does not answer {what} (a saved "
                         "calibrated model answers one design at a time; one calibrated "
                         "against an exponential model predicts but does not invert)",
                         BUILT_IN_WORDS)
    return model


CAPABILITY_WORDS = {"inverse": "the pressure for an angle",
                    "covered_slices": "a design search"}
