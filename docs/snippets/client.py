"""Predict a curve, then find the pressure for a target angle and designs for a target."""

import os

import httpx

url = os.environ.get("BALLOON_URL", "http://127.0.0.1:8000")
design = {"L_mm": 7.1, "t_mm": 0.5, "body_material": "pdms_1_10",
          "membrane_material": "ecoflex_00_30"}

with httpx.Client(base_url=url, timeout=60) as client:  # a design search takes seconds
    r = client.post("/v1/predict", json={"design": design, "pressures_pa": [500, 1000, 1500]})
    r.raise_for_status()
    pred = r.json()
    for p, a, lo, hi in zip(pred["pressure_pa"], pred["angle_deg"], pred["lower_deg"],
                            pred["upper_deg"], strict=True):
        print(f"{p:6.0f} Pa  {a:6.2f} deg  [{lo:.2f}, {hi:.2f}]")
    print("in domain:", pred["validity"]["in_domain"], pred["validity"]["flags"])

    r = client.post("/v1/inverse/pressure", json={"design": design, "angles_deg": [45]})
    r.raise_for_status()
    print(f"45 deg needs {r.json()['pressure_pa'][0]:.0f} Pa")

    target = {"kind": "angle_at_pressure", "pressure_pa": 1500, "angle_deg": 30}
    r = client.post("/v1/inverse", json={"target": target, "L_bounds_mm": [4.1, 15.1],
                                         "n_results": 3})
    r.raise_for_status()
    for c in r.json()["candidates"]:
        print(f"#{c['rank']}: L = {c['L_mm']:.2f} mm, t = {c['t_mm']:.2f} mm, "
              f"{c['body_material']}/{c['membrane_material']}")

    r = client.post("/v1/predict", json={"design": {**design, "t_mm": 99},
                                         "pressures_pa": [1000]})
    problem = r.json()  # errors are RFC 9457 problem documents naming the field and range
    print(r.status_code, problem["errors"][0]["field"], problem["errors"][0]["allowed"])
