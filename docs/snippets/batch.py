"""Query many designs and write one CSV row per (design, pressure) to stdout."""

import csv
import os
import sys

import httpx

url = os.environ.get("BALLOON_URL", "http://127.0.0.1:8000")
pressures_pa = [250, 500, 750, 1000, 1250, 1500]
designs = [{"L_mm": L, "t_mm": t} for L in (4.1, 7.1, 11.1, 15.1) for t in (0.5, 0.75, 1.0)]

out = csv.writer(sys.stdout)
out.writerow(["L_mm", "t_mm", "pressure_pa", "angle_deg", "lower_deg", "upper_deg",
              "in_domain"])
with httpx.Client(base_url=url, timeout=10) as client:
    for design in designs:
        r = client.post("/v1/predict", json={"design": design, "pressures_pa": pressures_pa})
        if r.status_code != 200:  # e.g. 422 outside the ranges: report and go on
            print(f"{design}: {r.json()['detail']}", file=sys.stderr)
            continue
        pred = r.json()
        for row in zip(pred["pressure_pa"], pred["angle_deg"], pred["lower_deg"],
                       pred["upper_deg"], strict=True):
            out.writerow([design["L_mm"], design["t_mm"], *row,
                          pred["validity"]["in_domain"]])
