"""Does ``time_s`` count from the pump's start? A clock that does not puts every
injected volume off by Q x (its offset).

The injected volume is Q x the pumping time since ``time_s`` = 0, the chamber at rest
(docs/measured-data.md). A lab's logger often starts elsewhere: at its first reading
(taken a reading interval into the pumping), or on a clock of its own. At 0 s the
chamber holds no injected fluid, so a reading at 0 s whose gauge already reads a good
part of the curve's top pressure says the pump ran before the clock started. Read as
given, such data were fitted as if the pump had put one interval less into every
reading: on FE data of a membrane 25 % stiffer than its preset, read every 2.5 s at
2 ul/s with the clock at the first reading, nothing was selected and 8.8 deg was
flagged as an effect outside the catalogue (1.04 deg with the pump's clock).
"""

from __future__ import annotations

#: a reading at 0 s above this fraction of its curve's top gauge pressure was pumped
#: (a gauge's zero error is at most a few per cent of a curve's range: 300 Pa, the
#: catalogue's plausible offset, is 12 % of a 2.5 kPa curve)
PRESSURISED_AT_ZERO = 0.2


def clock_warning(by_curve: dict[str, list[dict[str, object]]]
                  ) -> tuple[str, str, int | None] | None:
    """A warning (column, message, row) when curves read a pressurised chamber at
    ``time_s`` = 0 while the pump ran; None otherwise. ``by_curve``: each curve's rows
    (validated records with time_s and flow_ul_s), in file order."""
    early = []
    for cid, recs in by_curve.items():
        if any(r.get("time_s") != r.get("time_s") or r.get("flow_ul_s") != r.get("flow_ul_s")
               for r in recs):   # NaN: no clock or no flow rate, no injected volume
            return None
        top = max(abs(float(r["pressure_pa"])) for r in recs)  # type: ignore[arg-type]
        first = min(recs, key=lambda r: float(r["time_s"]))  # type: ignore[arg-type]
        p0 = abs(float(first["pressure_pa"]))  # type: ignore[arg-type]
        if (float(first["time_s"]) == 0.0 and float(first["flow_ul_s"]) > 0.0  # type: ignore
                and top > 0.0 and p0 > PRESSURISED_AT_ZERO * top):
            early.append((cid, p0, top))
    if not early:
        return None
    cid, p0, top = early[0]
    more = f" (and {len(early) - 1} more)" if len(early) > 1 else ""
    return ("time_s", f"curve_id {cid!r}{more} reads {p0:g} Pa at time_s = 0, {100 * p0 / top:.0f} "
            "% of its top pressure: time_s counts from the pump's start with the chamber "
            "at rest, so the pump seems to have run before the clock started and every "
            "injected volume (flow x time) is short by flow x that time; add it to time_s "
            "(a clock started at the first reading: add one reading interval)", None)
