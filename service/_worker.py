"""The body of a solve worker process (kept light: a spawned child imports only this,
the solve function's module and the domain types, not the web stack)."""

from __future__ import annotations

from typing import Any

from solver.errors import BalloonError

SolveFn = Any
PROGRESS_KEYS = ("step", "pressure_pa", "volume_ul", "angle_deg", "newton_iterations",
                 "cutbacks")


def child_main(solve_fn: SolveFn, design: Any, settings: Any, conn: Any) -> None:
    """Worker process: solve and report through ``conn`` (steps, then done or error)."""

    def on_step(info: dict[str, Any]) -> None:
        conn.send(("step", {k: _plain(info.get(k)) for k in PROGRESS_KEYS if k in info}))

    try:
        curve = solve_fn(design, settings, on_step=on_step)
        conn.send(("done", curve))
    except BalloonError as exc:
        conn.send(("error", str(exc)))
    except Exception as exc:  # noqa: BLE001 - reported to the client as the job's error
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


def _plain(value: Any) -> Any:
    if hasattr(value, "item"):
        value = value.item()
    return value


def default_solve(design: Any, settings: Any, on_step: Any = None) -> Any:
    """The FE solve (``solver.solve``), imported in the worker process only."""
    from solver import solve

    return solve(design, settings, on_step=on_step)
