#!/usr/bin/env bash
# Starts the 10 agents of team.toml as independent background processes, in a random order
# with random delays (as a supervisor might), waits for all of them and prints the team's
# assignment. Usage: examples/team/start-team.sh [path/to/admm-ta]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
admm_ta="${1:-$here/../../target/release/admm-ta}"
team="$here/team.toml"
pids=()
for id in $(seq 0 9 | shuf); do
    "$admm_ta" agent --team "$team" --robot "$id" > "$here/agent-$id.out" 2>&1 &
    pids+=($!)
    sleep "0.0$((RANDOM % 10))"
done
status=0
for pid in "${pids[@]}"; do wait "$pid" || status=1; done
if [ "$status" -ne 0 ]; then
    echo "an agent failed:" >&2
    grep -h . "$here"/agent-*.out >&2
    exit 1
fi
"$admm_ta" collect --team "$team" --check
