#!/bin/bash
# Makes the recorded sessions and golden PanelState logs in this folder: the
# console emulator (rise-panel) plays session.txt on a real transport on
# loopback, rise-hild reads it and records the session with --record:
#   can/       rise_console.yaml over socketcand (TCP):  console.log + panel_state.lcmlog
#   modbus/    rise_console_modbus.yaml over Modbus TCP: console.modbus.log + panel_state.lcmlog
#   split/     rise_console_split.yaml, sticks on socketcand + buttons on Modbus TCP
#   hid/       hid/pad.yaml over replay:// of the HID emulator's reports of
#              hid/session.txt (no uhid here: hil_hid_replay_test "[.golden]" writes them):
#              pad.hid + panel_state.lcmlog
# Each is checked with `rise-hild verify --record-dir` before it is kept.
# Run from anywhere after a build: bash tests/data/replay/make_goldens.sh [BUILD_DIR [NAME...]]
# (NAME: can, modbus, split, hid; default: all)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
bin=$(cd "${1:-$root/build}" && pwd)/bin
only=("${@:2}")
want() { [ ${#only[@]} -eq 0 ] || [[ " ${only[*]} " == *" $1 "* ]]; }
work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT
cd "$root"

# wait_for FILE REGEX: until a line matching REGEX (ERE) appears in FILE,
# 10 s at most. tail -F hands over each line as the peer writes it.
wait_for() {
  local line fd pid
  exec {fd}< <(exec timeout 10 tail -n +1 -F -- "$1" 2>/dev/null)
  pid=$!
  while IFS= read -r -u "$fd" line; do
    if [[ $line =~ $2 ]]; then
      kill "$pid" 2>/dev/null; exec {fd}<&-
      return 0
    fi
  done
  exec {fd}<&-
  echo "timed out waiting for '$2' in $1" >&2; cat "$1" >&2; return 1
}

port=$((30000 + $$ % 20000))
record() {  # record NAME PANEL HILD_SOURCES... -- EMULATOR_ARGS... [-- EMULATOR_ARGS...]
  want "$1" || return 0
  local name=$1 panel=$2; shift 2
  local sources=()
  while [ "$1" != "--" ]; do sources+=(--source "$1"); shift; done
  shift
  local pids=() n=0 args=()
  for a in "$@" --; do
    if [ "$a" = "--" ]; then
      "$bin/rise-panel" emulate --panel "$panel" --script "$here/session.txt" --start-on-feedback "${args[@]}" \
        > "$work/$name-panel$n.log" 2>&1 &
      pids+=($!)
      wait_for "$work/$name-panel$n.log" "rise-panel ready"
      n=$((n + 1)); args=()
    else
      args+=("$a")
    fi
  done
  rm -rf "${work:?}/$name"
  "$bin/rise-hild" --panel "$panel" "${sources[@]}" --id golden --lcm 'memq://' --record "$work/$name" \
    > "$work/$name-hild.log" 2>&1 &
  local hild=$!
  wait "${pids[@]}"
  wait_for "$work/$name-hild.log" "failsafe: .*disconnected"
  kill -TERM $hild; wait $hild
  "$bin/rise-hild" verify --panel "$panel" --record-dir "$work/$name"
  rm -rf "${here:?}/$name"; mkdir -p "$here/$name"
  cp "$work/$name"/* "$here/$name/"
  ls -l "$here/$name"
}

record can panels/definitions/rise_console.yaml "socketcand://127.0.0.1:$port/can0" \
  -- --can "socketcand+listen://127.0.0.1:$port/can0"
record modbus panels/definitions/rise_console_modbus.yaml "modbus+tcp://127.0.0.1:$((port + 1))" \
  -- --modbus "modbus+tcp-listen://127.0.0.1:$((port + 1))?unit=1"
record split panels/definitions/rise_console_split.yaml "socketcand://127.0.0.1:$((port + 2))/can0" \
  "modbus+tcp://127.0.0.1:$((port + 3))" \
  -- --source sticks --can "socketcand+listen://127.0.0.1:$((port + 2))/can0" \
  -- --source buttons --modbus "modbus+tcp-listen://127.0.0.1:$((port + 3))?unit=1"

# hid/: the daemon reads the emulated pad's reports from replay:// as it
# reads the device; the replay's end fails it safe after the re-plug
# (reconnects=1), which the status line shows.
if want hid; then
  input=$work/hid-input.hid
  RISE_HID_GOLDEN_INPUT=$input "$bin/../tests/hil/hil_hid_replay_test" "[.golden]" > "$work/hid-input.log"
  "$bin/rise-hild" --panel "$here/hid/pad.yaml" --source "replay://$input" --id golden --lcm 'memq://' \
    --status-every 0.05 --record "$work/hid" > "$work/hid-hild.log" 2>&1 &
  hild=$!
  wait_for "$work/hid-hild.log" "source pad: connected=false .* reconnects=1 "
  kill -TERM $hild; wait $hild
  "$bin/rise-hild" verify --panel "$here/hid/pad.yaml" --record-dir "$work/hid"
  cp "$work/hid/pad.hid" "$work/hid/panel_state.lcmlog" "$here/hid/"
  ls -l "$here/hid"
fi
