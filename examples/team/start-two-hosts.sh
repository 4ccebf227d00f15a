#!/usr/bin/env bash
# Runs the two "machines" of two-hosts.toml on this one: each host is its own process group
# (its `admm-ta host` and its five agents), and the hosts talk Zenoh over 127.0.0.1. Then it
# collects the team's assignment. Usage: examples/team/start-two-hosts.sh [path/to/admm-ta]
# (built with `cargo build --release --features zenoh`).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
admm_ta="${1:-$here/../../target/release/admm-ta}"
team="$here/two-hosts.toml"
start_host() { # NAME FIRST LAST: the host's router/bridge and its agents, one process group
    setsid bash -c '
        admm_ta="$1"; team="$2"; name="$3"; here="$4"
        "$admm_ta" host --team "$team" --name "$name" > "$here/host-$name.out" 2>&1 &
        pids=($!)
        for id in $(seq "$5" "$6"); do
            "$admm_ta" agent --team "$team" --robot "$id" > "$here/agent-$id.out" 2>&1 &
            pids+=($!)
        done
        status=0
        for pid in "${pids[@]}"; do wait "$pid" || status=1; done
        exit "$status"
    ' _ "$admm_ta" "$team" "$1" "$here" "$2" "$3"
}
start_host alpha 0 4 & alpha=$!
start_host beta 5 9 & beta=$!
status=0
wait "$alpha" || status=1
wait "$beta" || status=1
if [ "$status" -ne 0 ]; then
    echo "the team failed:" >&2
    grep -h . "$here"/host-*.out "$here"/agent-*.out >&2
    exit 1
fi
cat "$here"/host-*.out
"$admm_ta" collect --team "$team" --check
