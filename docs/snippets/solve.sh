# Queue an FE solve of a new design (needs the server's API key), then poll the job
: "${BALLOON_API_KEY:?set BALLOON_API_KEY to the API key of the server (POST /v1/solve needs it)}"
URL="${BALLOON_URL:-http://127.0.0.1:8000}"
JOB=$(curl -s -X POST "$URL/v1/solve" \
  -H "Content-Type: application/json" -H "X-API-Key: $BALLOON_API_KEY" \
  -d '{"design": {"L_mm": 9.1, "t_mm": 0.6}}')   # default settings: the database's own solve
echo "$JOB"
curl -s "$URL/v1/jobs/$(echo "$JOB" | python3 -c 'import json, sys; print(json.load(sys.stdin)["id"])')"
