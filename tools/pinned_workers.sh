#!/usr/bin/env bash
# Run the same resumable command in N processes at once, process i pinned to core i with
# one XLA thread (benchmarks/bench_parallel.py: on this 2-core machine two pinned Ant PPO
# runs train 2.06x the env-steps/s of one run alone). Sweeps whose runs take locks
# (sgb.runlock) share their runs out this way.
#   tools/pinned_workers.sh N LOGDIR command [args...]
set -euo pipefail
n=$1; logs=$2; shift 2
mkdir -p "$logs"
for ((i = 0; i < n; i++)); do
    XLA_FLAGS="${XLA_FLAGS:-} --xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1" \
        taskset -c "$((i % $(nproc)))" "$@" > "$logs/worker_$i.log" 2>&1 &
    sleep 20  # the first takes its run before the second looks
done
wait
