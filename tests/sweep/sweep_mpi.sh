#!/usr/bin/env bash
# sinew-sweep across MPI ranks on the CPU backend (ctest: sweep_mpi; skipped, exit 77, when the
# build has no MPI). On one machine with Open MPI's mpirun:
#  1. one process and `mpirun -n 3` (rank 0 hands out, ranks 1 and 2 run) give the same table,
#     bit for bit per run (every column but wall_time_s), with the deliberately unstable run
#     recorded as unstable (exit status 3: not every run completed);
#  2. a rank killed (SIGKILL) mid-sweep loses only the runs in flight (mpirun then ends the job:
#     the other rank's run stops with a checkpoint); the finished runs stay, and the same command
#     again completes the table, equal to the one-process table.
# Usage: sweep_mpi.sh SWEEP GENERATE MPIRUN WORK
set -euo pipefail
sweep=$1 generate=$2 mpirun=$3 work=$4
if [[ -z "$mpirun" ]]; then
  echo "SKIPPED: sinew-sweep was built without MPI (install libopenmpi-dev: scripts/install-deps)"
  exit 77
fi
fail() { echo "FAILED: $*" >&2; exit 1; }
trap 'echo "FAILED: line $LINENO: $BASH_COMMAND exited $?" >&2' ERR
mpi=("$mpirun" --oversubscribe -n 3)
[[ $(id -u) -eq 0 ]] && mpi=("$mpirun" --oversubscribe --allow-run-as-root -n 3)
export OMP_WAIT_POLICY=PASSIVE

rm -rf "$work" && mkdir -p "$work" && cd "$work"
# A 10 mm cube of 8 x 8 x 8 voxels (E = 174 kPa, nu = 0.45) settling on its base under gravity.
"$generate" box --dims 8 8 8 --voxel-size 0.00125 --material tissue:174000:0.45:1000 -o cube.h5 -q
cat > cube.yaml <<'YAML'
title: cube under gravity
model: cube.h5
effects: [elasticity, hourglass, damping, gravity]
duration: 0.1
damping: 400
boundary_conditions:
  - {type: fixed, set: z_min}
output: {interval: 0.05, probe_interval: 0.001}
probes:
  - {name: base, type: reaction, set: z_min}
  - {name: top, type: displacement, point: [0.005, 0.005, 0.01]}
YAML
cat > sweep.yaml <<'YAML'
version: 1
scene: cube.yaml
list:
  - {damping: 300}
  - {damping: 400}
  # Five runs per working rank, so that a kill after the first finished run finds the killed rank
  # with runs still to do (with three, the other rank sometimes finished the table first).
  - {damping: 500}
  - {damping: 600}
  # Deliberately unstable: a fixed step 20 times the critical one, forced.
  - {time_step: {mode: fixed, value: 0.001, force: true}}
grid:
  gravity: [[0, 0, -9.81], [0, 0, -3.7]]
figures:
  - {name: base_fz, probe: base, value: fz}
  - {name: top_uz_at_20ms, probe: top, value: uz, at: 0.02}
  - {name: top_uz_max, probe: top, value: uz, stat: max_abs}
  - {name: strain_end, energy: strain}
run: {device: cpu, threads: 1}
YAML

# Every column but the last (wall_time_s).
table() { cut -d, -f1-$(($(head -1 "$1" | tr ',' '\n' | wc -l) - 1)) "$1"; }

rc=0
"$sweep" sweep.yaml -o one -q || rc=$?
[[ $rc -eq 3 ]] || fail "one process: exit status $rc, expected 3 (one unstable run)"
[[ $(grep -c ',completed,' one/sweep_table.csv) -eq 8 ]] || fail "one process: 8 completed runs expected: $(cat one/sweep_table.csv)"
[[ $(grep -c ',unstable,' one/sweep_table.csv) -eq 2 ]] || fail "one process: 2 unstable runs expected: $(cat one/sweep_table.csv)"

# mpirun_matches_one_process WHAT OUT: the sweep under mpirun -n 3 into OUT exits 3 (the unstable
# runs) with the one-process table.
mpirun_matches_one_process() {
  local rc=0
  "${mpi[@]}" "$sweep" sweep.yaml -o "$2" -q > "$2.log" 2>&1 || rc=$?
  [[ $rc -eq 3 ]] || fail "$1: exit status $rc, expected 3: $(cat "$2.log")"
  diff <(table one/sweep_table.csv) <(table "$2/sweep_table.csv") ||
    fail "$1 gives another table than one process"
}
mpirun_matches_one_process "mpirun -n 3" three
echo "1 and 3 ranks: the same table ($(($(wc -l < one/sweep_table.csv) - 1)) runs)"

# in_flight: true when a run folder has no finished summary yet (a run is going on).
in_flight() {
  local d
  for d in killed/run_*/; do
    [[ -f "$d/scene.yaml" ]] || continue
    grep -qs -e '"status": "completed"' -e '"status": "unstable"' "$d/run_summary.json" || return 0
  done
  return 1
}

# 2. Kill rank 2 once a run has finished while another is going on.
"${mpi[@]}" "$sweep" sweep.yaml -o killed -q > killed_first.log 2>&1 &
launcher=$!
victim=""
for _ in $(seq 1 3000); do
  for p in $(pgrep -P "$launcher"); do
    if tr '\0' '\n' < "/proc/$p/environ" 2>/dev/null | grep -qx 'OMPI_COMM_WORLD_RANK=2'; then victim=$p; fi
  done
  [[ -n "$victim" ]] && break
  sleep 0.01
done
[[ -n "$victim" ]] || fail "rank 2 was not found: $(cat killed_first.log)"
# The victim is known beforehand, so the kill follows the check at once.
for _ in $(seq 1 3000); do
  grep -qs '"status": "completed"' killed/run_*/run_summary.json && in_flight && break
  sleep 0.01
done
kill -9 "$victim"
rc=0
wait "$launcher" || rc=$?
[[ $rc -ne 0 ]] || fail "mpirun exited 0 although rank 2 was killed"
finished=$(cat killed/run_*/run_summary.json 2>/dev/null | grep -c -e '"status": "completed"' -e '"status": "unstable"' || true)
echo "killed rank 2: mpirun exit $rc, $finished of 10 runs finished"
[[ $finished -ge 1 && $finished -lt 10 ]] || fail "expected some but not all runs finished, got $finished"
mpirun_matches_one_process "the rerun after the killed rank" killed
echo "the rerun completed the table, equal to one process's"
