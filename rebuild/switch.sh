#!/usr/bin/env bash
# The switch to the balanced mesh, steps 2-5 of rebuild/README.md, in a worktree of the
# branch switch-balanced (rebased on main):
#
#   git worktree add ../switch switch-balanced
#   rebuild/switch.sh ../switch [--prefix]      # from the main checkout, its venv active
#
# Copies the rebuilt files (a committed checkpoint when --prefix: the rebuild is still
# running), refits in one command, and compares the new emulator on the balanced held-out
# sets with the figures a switch must match (README.md here). It commits nothing.
set -euo pipefail
MAIN=$(cd "$(dirname "$0")/.." && pwd)
SW=$(cd "$1" && pwd)
PY=${PYTHON:-$MAIN/.venv/bin/python}
BALLOON=$(dirname "$PY")/balloon
if [ "${2:-}" = "--prefix" ]; then
  git -C "$MAIN" show HEAD:rebuild/curves-balanced.h5 > "$SW/service/data/curves.h5"
else
  if pgrep -f "precompute grids/balanced-mesh.toml --db rebuild/curves-balanced.h5" >/dev/null; then
    echo "the rebuild is still running: wait, or pass --prefix" >&2
    exit 1
  fi
  cp "$MAIN/rebuild/curves-balanced.h5" "$SW/service/data/curves.h5"
fi
cp "$MAIN/rebuild/band-calibration-balanced.h5" "$SW/service/data/band-calibration.h5"
cd "$SW"
export PYTHONPATH="$SW" OMP_NUM_THREADS=1
"$PY" -c "
import h5py
with h5py.File('service/data/curves.h5', 'r') as f:
    print('records', len(f['records']))"
"$BALLOON" fit --db service/data/curves.h5 -o service/data/surrogate.json \
  --report-dir docs/fit-report --emulator-output service/data/emulator.json \
  --band-calibration-db service/data/band-calibration.h5 --no-progress
for set in 2028 2029; do
  echo "-- held-out $set (balanced)"
  "$PY" benchmarks/bench_emulator.py --heldout "$MAIN/rebuild/heldout-$set-balanced.h5" \
    --axis both | grep -E "^all|^query"
done
echo "to match: 27 of 34 curves by pressure, 24 of 34 by volume; coverage 0.977 / 0.888"
