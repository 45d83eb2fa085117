"""Rank your designs by the pressure they need for 45 deg: a CSV of designs in (columns
L_mm, t_mm and any of T_mm, b_mm, h_mm, W_mm, body_material, membrane_material, plus your
own), the same rows out on stdout with the answer, the error of a refused design, and the
model file's identity; progress on stderr. Usage: python batch.py designs.csv > out.csv"""

import csv
import os
import sys

import httpx

url = os.environ.get("BALLOON_URL", "http://127.0.0.1:8000")
angle_deg = 45
fields = {"L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "W_mm", "body_material", "membrane_material"}


def value(text):  # a number as a number; any other text as written (the server names it)
    try:
        return float(text)
    except ValueError:
        return text


def answer(client, row):  # pressure, its band, flags, error
    if None in row or None in row.values():  # a cell past the header ("7,1" in a ','
        return ["", "", "", "", "the row's cells do not match the header"]  # file), or short
    design = {key: value(cell) for key, cell in row.items() if key in fields and cell}
    r = client.post("/v1/inverse/pressure", json={"design": design, "angles_deg": [angle_deg]})
    if r.status_code != 200:  # a refused design keeps its row: the field, its range
        return ["", "", "", "", r.json()["detail"]]
    inv = r.json()
    return [inv["pressure_pa"][0], inv["lower_pa"][0], inv["upper_pa"][0],
            " ".join(inv["validity"]["flags"]), ""]


with open(sys.argv[1], newline="", encoding="utf-8-sig") as file:
    reader = csv.DictReader(file)
    designs = list(reader)
with httpx.Client(base_url=url, timeout=30) as client:
    health = client.get("/v1/health").json()  # the model file that answers, in every row
    identity = [health["emulator"]["file"], health["emulator"]["sha256"], health["version"]]
    out = csv.writer(sys.stdout)
    out.writerow([*reader.fieldnames, "pressure_pa", "lower_pa", "upper_pa", "flags", "error",
                  "model_file", "model_sha256", "balloon_version"])
    for k, row in enumerate(designs, start=1):
        result = answer(client, row)
        out.writerow([*(row.get(name) for name in reader.fieldnames), *result, *identity])
        print(f"\r{k}/{len(designs)} designs", end="\n" if k == len(designs) else "",
              file=sys.stderr)
