"""The syringe-pump view: the angle after a time at a flow rate, and the fluid for an angle."""

import os

import httpx

url = os.environ.get("BALLOON_URL", "http://127.0.0.1:8000")
design = {"L_mm": 7.1, "t_mm": 0.5}

with httpx.Client(base_url=url, timeout=10) as client:
    # what angle after 2, 4, 8 s at 2.5 ul/s, and what does a gauge at the pump read?
    r = client.post("/v1/predict", json={"design": design, "times_s": [2, 4, 8],
                                         "flow_ul_s": 2.5, "inlet": {}})
    r.raise_for_status()
    pred = r.json()
    for t, v, p, gauge, a in zip(pred["time_s"], pred["volume_ul"], pred["pressure_pa"],
                                 pred["pump_pressure_pa"], pred["angle_deg"], strict=True):
        print(f"{t:4.1f} s  {v:5.1f} ul  chamber {p:5.0f} Pa  pump gauge {gauge:5.0f} Pa  "
              f"{a:5.1f} deg")
    # how much fluid, and how long at 2.5 ul/s, to reach 45 deg?
    r = client.post("/v1/inverse/pressure", json={"design": design, "angles_deg": [45],
                                                  "flow_ul_s": 2.5})
    r.raise_for_status()
    inv = r.json()
    print(f"45 deg needs {inv['volume_ul'][0]:.1f} ul "
          f"[{inv['volume_lower_ul'][0]:.1f}, {inv['volume_upper_ul'][0]:.1f}], "
          f"{inv['time_s'][0]:.1f} s at 2.5 ul/s")
