# Angle, volume and chamber pressure after 2, 4, 8 s of a syringe pump at 2.5 ul/s
curl -s -X POST "${BALLOON_URL:-http://127.0.0.1:8000}/v1/predict" \
  -H "Content-Type: application/json" \
  -d '{"design": {"L_mm": 7.1, "t_mm": 0.5}, "times_s": [2, 4, 8], "flow_ul_s": 2.5}'
