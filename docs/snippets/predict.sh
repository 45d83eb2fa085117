# Angle against pressure for the paper's standard design (PDMS 1:10 body, Ecoflex 00-30 membrane)
curl -s -X POST "${BALLOON_URL:-http://127.0.0.1:8000}/v1/predict" \
  -H "Content-Type: application/json" \
  -d '{"design": {"L_mm": 7.1, "t_mm": 0.5}, "pressures_pa": [500, 1000, 1500, 2000]}'
