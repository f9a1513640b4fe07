#!/usr/bin/env bash
# Run the test suite N times in a row (default 3) while BURNERS processes (default 2) keep the CPUs
# busy, as on a shared CI machine; stops at the first failing run. Extra arguments go to pytest.
#   scripts/loaded_suite.sh                 # 3 full runs beside 2 CPU burners
#   RUNS=1 BURNERS=2 scripts/loaded_suite.sh tests/integration/rbnx
# The burners are this script's own children, stopped by PID on exit.
set -euo pipefail
runs="${RUNS:-3}"
burners="${BURNERS:-2}"
py="${PYTHON:-python}"
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
trap cleanup EXIT
for _ in $(seq 1 "$burners"); do
  "$py" -c "while True: pass" &
  pids+=("$!")
done
for i in $(seq 1 "$runs"); do
  echo "loaded_suite.sh: run $i/$runs beside $burners CPU burner(s)"
  "$py" -m pytest -q "$@"
done
echo "loaded_suite.sh: $runs/$runs runs passed"
