#!/usr/bin/env bash
# The study scripts' --help (scripts/accuracy-study, accuracy-sweeps, wrinkle-study): prints the
# usage and exits 0 at once, without configuring or building anything.
# Before --help was handled, accuracy-study passed it on and started configuring a build folder.
# Usage: script_help.sh SOURCE_DIR WORK_DIR
set -euo pipefail
src=$1
work=$2
rm -rf "$work"
mkdir -p "$work"
fail=0
for s in accuracy-study accuracy-sweeps wrinkle-study; do
  build="$work/build_$s"
  rc=0
  out=$(SINEW_BUILD_DIR="$build" timeout 60 "$src/scripts/$s" --help 2>&1) || rc=$?
  if [[ $rc -ne 0 ]]; then
    echo "FAIL: scripts/$s --help exited $rc"; fail=1
  fi
  if [[ "$out" != *"scripts/$s ["* ]]; then
    echo "FAIL: scripts/$s --help does not print its usage line 'scripts/$s [...'"; fail=1
  fi
  if [[ -e "$build" ]]; then
    echo "FAIL: scripts/$s --help created the build folder $build"; fail=1
  fi
done
[[ $fail -eq 0 ]] && echo "script_help: accuracy-study, accuracy-sweeps, wrinkle-study --help: usage, exit 0, nothing built"
exit $fail
