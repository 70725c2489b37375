#!/usr/bin/env bash
# chladni play against JACK's dummy driver (a server of its own, started here): 10 s of a scene
# on the CPU backend with no callback late and no underrun the client caused.
#
# The server runs with real-time scheduling where the machine allows it (root, or rtprio), so
# that its timer and the client's thread wake on time; elsewhere it runs without, and then wakes
# late now and then and reports that as an xrun to every client, so underruns are checked
# against the server's own late wake-ups in its log over the same time. A client "not finished"
# at a cycle's start is the client's fault only if its callback ran long, which "late
# callbacks" measures; on a shared machine a thread can also be scheduled late, so a run with
# such a report but no late callback is tried again, up to three runs. A late callback, a short
# play or an error fails at once.
# With more arguments (--churn N: a spawn storm through the C API beside the scene) they go to
# chladni play, and the storm must have spawned at least N objects a second for the 10 s.
# Usage: play_test.sh CHLADNI SCENE [PLAY OPTIONS...]
set -euo pipefail
chladni=$1 scene=$2
shift 2
extra=("$@")
tmp=$(mktemp -d)
export JACK_DEFAULT_SERVER="chladni_test_$$"
server=
stop_server() {
  if [ -n "$server" ]; then kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; fi
  server=
}
trap 'stop_server; rm -rf "$tmp"' EXIT

start_server() {
  local mode
  for mode in --realtime --no-realtime; do
    : >"$tmp/jackd.log"
    jackd -n "$JACK_DEFAULT_SERVER" "$mode" -d dummy -r 48000 -p 256 >"$tmp/jackd.log" 2>&1 &
    server=$!
    if jack_wait -s "$JACK_DEFAULT_SERVER" -w -t 10 >/dev/null 2>&1 && kill -0 "$server" 2>/dev/null; then
      echo "jackd $mode"
      return 0
    fi
    stop_server
  done
  echo "jackd would not start:" >&2
  cat "$tmp/jackd.log" >&2
  return 1
}

# One run; returns 0 clean, 1 failed, 3 only the server's or the scheduler's xruns.
play_once() {
  start_server || return 1
  local before after late underruns woke
  before=$(grep -c 'Process XRun' "$tmp/jackd.log" || true)
  "$chladni" play "$scene" --api jack --duration 10 --threads 1 "${extra[@]}" |
    tee "$tmp/play.log" || return 1
  after=$(grep -c 'Process XRun' "$tmp/jackd.log" || true)
  late=$(sed -nE 's/^late callbacks ([0-9]+), underruns ([0-9]+).*/\1/p' "$tmp/play.log")
  underruns=$(sed -nE 's/^late callbacks ([0-9]+), underruns ([0-9]+).*/\2/p' "$tmp/play.log")
  grep -q '^played 10.000 s' "$tmp/play.log" || return 1
  if [ "${#extra[@]}" -ge 2 ] && [ "${extra[0]}" = --churn ]; then
    local spawned
    spawned=$(sed -nE 's/^churn: ([0-9]+) steel bars.*/\1/p' "$tmp/play.log")
    # 10 s of play, less the stream's start: 95 % of the rate asked for.
    [ "${spawned:-0}" -ge $((extra[1] * 95 / 10)) ] || { echo "only ${spawned:-0} spawned" >&2; return 1; }
  fi
  woke=$((after - before))
  echo "late callbacks $late, underruns $underruns, server's own late wake-ups $woke"
  [ "$late" -eq 0 ] || return 1
  local status=0
  if [ "$underruns" -gt "$woke" ]; then status=3; fi
  if grep -i 'not finished' "$tmp/jackd.log"; then status=3; fi
  stop_server
  return $status
}

for attempt in 1 2 3; do
  status=0
  play_once || status=$?
  [ "$status" -eq 0 ] && exit 0
  [ "$status" -eq 3 ] || exit 1
  echo "run $attempt: xruns with every callback on time (a late wake-up); trying again"
done
echo "three runs, each with xruns" >&2
exit 1
