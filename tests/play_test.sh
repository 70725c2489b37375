#!/usr/bin/env bash
# chladni play against JACK's dummy driver (a server of its own, started here): 10 s of a scene
# on the CPU backend with no callback late and no underrun the client caused. The dummy driver
# runs on timers: without real-time scheduling it wakes late now and then and reports that as
# an xrun to every client, so underruns are checked against the server's own late wake-ups in
# its log over the same time.
# Usage: play_test.sh CHLADNI SCENE
set -euo pipefail
chladni=$1 scene=$2
tmp=$(mktemp -d)
export JACK_DEFAULT_SERVER="chladni_test_$$"
jackd -n "$JACK_DEFAULT_SERVER" --no-realtime -d dummy -r 48000 -p 256 >"$tmp/jackd.log" 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null; wait "$server" 2>/dev/null; rm -rf "$tmp"' EXIT
jack_wait -s "$JACK_DEFAULT_SERVER" -w -t 10 >/dev/null
before=$(grep -c 'Process XRun' "$tmp/jackd.log" || true)
"$chladni" play "$scene" --api jack --duration 10 --threads 1 | tee "$tmp/play.log"
after=$(grep -c 'Process XRun' "$tmp/jackd.log" || true)
late=$(sed -nE 's/^late callbacks ([0-9]+), underruns ([0-9]+).*/\1/p' "$tmp/play.log")
underruns=$(sed -nE 's/^late callbacks ([0-9]+), underruns ([0-9]+).*/\2/p' "$tmp/play.log")
grep -q '^played 10.000 s' "$tmp/play.log"
echo "late callbacks $late, underruns $underruns, server's own late wake-ups $((after - before))"
test "$late" -eq 0
test "$underruns" -le $((after - before))
if grep -i 'not finished' "$tmp/jackd.log"; then exit 1; fi
