"""Add the pressure-volume relations to a surrogate file fitted before format version 3,
from the records of its own provenance, its fitted parameters unchanged:

    python -m surrogate.exponential.add_volumes --db service/data/curves.h5 \\
        -i service/data/surrogate.json -o service/data/surrogate.json

(``balloon fit`` makes them itself; this keeps a shipped fit whose figures the docs
discuss while its database has grown since.)
"""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    from surrogate.dataset import curves_from_store
    from surrogate.exponential.file import load_surrogate, save_surrogate
    from surrogate.exponential.fit_from_curves import attach_volume_relations

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--db", required=True, help="the curve database the file was fitted from")
    ap.add_argument("-i", "--input", required=True, help="surrogate file (JSON)")
    ap.add_argument("-o", "--output", required=True, help="surrogate file to write (JSON)")
    args = ap.parse_args(argv)
    s = load_surrogate(args.input)
    curves, _ = curves_from_store(args.db)
    command = "python -m surrogate.exponential.add_volumes " + " ".join(sys.argv[1:] if
                                                                        argv is None else argv)
    out = attach_volume_relations(s, curves, float(s.provenance.get("level", 0.95)), command)
    for fam in out.family_fits:
        lodo = fam.volume.lodo if fam.volume else {}
        print(f"{fam.label}: " + (f"{lodo.get('n_designs')} designs, LODO RMSE "
                                  f"{lodo.get('rmse_ul', float('nan')):.2f} ul "
                                  f"({lodo.get('rmse_percent', float('nan')):.1f} %)"
                                  if fam.volume else "no volumes"))
    print(f"wrote {save_surrogate(out, args.output)}")
    return 0


if __name__ == "__main__":
    from solver.errors import BalloonError

    try:
        sys.exit(main())
    except (BalloonError, OSError) as exc:   # a bad --db or -i file: one line, file intact
        print(f"add_volumes: error: {exc}", file=sys.stderr)
        sys.exit(2)
