#!/bin/sh
# Run the black-box Modbus bad-input harness (../shared/bench/fuzz, never copied here)
# against a real `fieldtwin run` serving plant.toml: Modbus TCP, then the RTU pty line.
#   benchmarks/fuzz/run.sh [extra harness options, e.g. --budget 120 -v]
# Exit status: the worst of the two harness runs (0: kept answering, no crash/stall/dead).
set -u
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
harness=${FUZZ_HARNESS:-$root/../shared/bench/fuzz/modbus_badinput.py}
[ -f "$harness" ] || harness=/work/shared/bench/fuzz/modbus_badinput.py
python=${PYTHON:-$root/.venv/bin/python}
out=${FUZZ_OUT:-/tmp/fieldtwin-fuzz}
mkdir -p "$out"

"$python" -m fieldtwin run "$here/plant.toml" --no-live >"$out/fieldtwin.log" 2>&1 &
pid=$!
trap 'kill "$pid" 2>/dev/null; wait "$pid" 2>/dev/null' EXIT INT TERM
tries=0
until grep -q "^running" "$out/fieldtwin.log" 2>/dev/null; do
    tries=$((tries + 1))
    if [ "$tries" -gt 150 ] || ! kill -0 "$pid" 2>/dev/null; then
        echo "fieldtwin run did not start:" >&2; cat "$out/fieldtwin.log" >&2; exit 2
    fi
    sleep 0.1
done
port=$(sed -n 's|^listening: modbus-tcp tcp://127.0.0.1:\([0-9]*\) .*|\1|p' "$out/fieldtwin.log")
pty=$(sed -n 's|^listening: modbus-rtu pty \(/dev/pts/[0-9]*\) .*|\1|p' "$out/fieldtwin.log")
echo "fieldtwin pid $pid: tcp port $port, rtu pty $pty"

# The TES 32EST map (TES 6.2): words 000h..1A4h (421 words) answer; bits are addressed
# word x 10h + bit (TES 7.1.2), so the bit tables reach 16 x further (see docs/modbus.md).
# Writes go to 012h (OR mask of output word 0, RW in RAM): word 000h is the status word,
# whose bits the master can only reset (TES 6.2.1).
common="--unit 1 --addr 0 --map-size 421 --write-addr 18 --server-pid $pid"
"$python" "$harness" tcp --port "$port" $common --json "$out/tcp.json" "$@"
tcp=$?
"$python" "$harness" rtu --device "$pty" --baud 38400 $common --json "$out/rtu.json" "$@"
rtu=$?
kill -0 "$pid" 2>/dev/null || { echo "fieldtwin run exited during the harness" >&2; exit 1; }
echo "harness exit status: tcp $tcp, rtu $rtu (logs and JSON in $out)"
[ "$tcp" -ge "$rtu" ] && exit "$tcp"
exit "$rtu"
