"""The batch precompute job: grid file -> missing designs -> solves -> curve database.

    from solver.precompute import load_grid, precompute
    summary = precompute(load_grid("grids/default.toml"), "curves.h5", workers=2)

Grid format: ``solver.precompute.grid``; the job's rules: ``solver.precompute.job``;
process pool or Dask: ``solver.precompute.backends``.
"""

from solver.precompute.grid import Grid, GridError, GridPoint, load_grid, parse_grid
from solver.precompute.job import JobSummary, plan, precompute, run_job, solve_point

__all__ = ["Grid", "GridError", "GridPoint", "JobSummary", "load_grid", "parse_grid", "plan",
           "precompute", "run_job", "solve_point"]
