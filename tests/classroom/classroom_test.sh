#!/bin/bash
# A classroom across machines, on this one machine. Each "host" is a network
# namespace with its own eth0 on one bridge (in a namespace of its own, the
# LAN), and LCM multicast with ttl=1 routed out of eth0
# (ip route add 224.0.0.0/4 dev eth0), as README "A classroom on a LAN" says:
#   instructor: rise-instructor serve (the console page, /api/trainees)
#   stations A, B, C: rise-panel emulate (the console) → rise-hild → rise-sim,
#     and rise-trainer run-task beside them; B's processes all run with the
#     wall clock 7 s ahead (libfaketime), as on a host whose clock is off.
# Checks:
#   1. the instructor lists every trainee, live, with PanelState, RobotState
#      and TaskStatus; it measures B's clock at +7 s (±100 ms) and the others'
#      at 0 (±100 ms), and judges B's states fresh (age on arrival < 500 ms);
#   2. a fault injected from the console into B (signed, stamped in B's
#      clock) applies there; A and C have no active fault, and no command
#      was rejected; so does one from `rise-instructor inject`, which
#      measures B's clock itself;
#   3. C's link cut (ip link set eth0 down in C): C's rise-sim stops its
#      robot ("no panel state") within its 100 ms panel timeout (+ one 20 ms
#      state period and the log's slack), /api/trainees shows C lost within
#      1 s, and so does the console page's trainee list (headless Chromium);
#      A and B stay live; C stays lost for the 2 s its link is down;
#      `rise-instructor list`, listening across the cut, marks C (only) LOST;
#   4. the link back (ip link set up, the multicast route again as ifup
#      would add it): C live again on the API and the page, its motors enabled.
# Every name carries this script's pid; the namespaces and the processes in
# them go on any exit (trap). Exit 77: skipped (not root, no namespaces, a
# tool or the built pages missing), with why.
#
# usage: classroom_test.sh BIN_DIR SOURCE_DIR
set -u -o pipefail
BIN=${1:?usage: classroom_test.sh BIN_DIR SOURCE_DIR}
SRC=${2:?usage: classroom_test.sh BIN_DIR SOURCE_DIR}
P=$$
SKEW_S=7
LOST_AFTER_MS=500
PANEL_TIMEOUT_MS=100
LCM="udpm://239.255.76.67:7667?ttl=1"
PORT=8080
TOKEN="classroom-$P"
LAN=rlan$P INS=rins$P
HOSTS=(rsa$P rsb$P rsc$P)
IDS=(a$P b$P c$P)
LETTERS=(a b c)
WORK=""
PIDS=()

skip() { echo "SKIPPED: $*"; exit 77; }
now_ms() { date +%s%3N; }
log() { echo "classroom $(date +%T.%3N): $*"; }
# The lines of a log as its program writes them: follow FILE LIMIT_S opens fd
# FOLLOW_FD on FILE from its first line, woken by each write (tail -F, inotify),
# for at most LIMIT_S; unfollow closes it and ends the tail.
follow() {
  exec {FOLLOW_FD}< <(exec timeout "$2" tail -n +1 -F "$1" 2>/dev/null)
  FOLLOW_PID=$!
}
unfollow() { kill "$FOLLOW_PID" 2>/dev/null; exec {FOLLOW_FD}<&-; }
# FILE ERE LIMIT_S [N]: prints the Nth line of FILE matching ERE once it is
# written; false when it is not within LIMIT_S.
wait_line() {
  local out
  follow "$1" "$3"
  out=$(grep -m "${4:-1}" -E "$2" <&"$FOLLOW_FD" | tail -n 1)
  unfollow
  [ -n "$out" ] && printf '%s\n' "$out"
}

[ "$(id -u)" -eq 0 ] || skip "needs root to create network namespaces (ip netns add)"
for tool in ip curl jq; do command -v "$tool" >/dev/null || skip "$tool is not installed (run.sh's packages)"; done
FAKETIME_LIB=$(ls /usr/lib/*/faketime/libfaketime.so.1 2>/dev/null | head -1)
[ -n "$FAKETIME_LIB" ] || skip "libfaketime is not installed (Debian package faketime)"
for p in rise-sim rise-hild rise-panel rise-trainer rise-instructor; do
  [ -x "$BIN/$p" ] || skip "$BIN/$p is not built"
done
[ -f "$SRC/instructor/web/dist/index.html" ] || skip "the console pages are not built (run.sh's web_setup)"
if ! err=$(ip netns add "$LAN" 2>&1); then skip "cannot create a network namespace: $err"; fi

WORK=$(mktemp -d /tmp/rise-classroom-XXXXXX)

cleanup() {
  local code=$?
  # Each child waited for as it exits on SIGTERM; a watchdog kills what is
  # left after 3 s.
  for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null; done
  (sleep 3; kill -KILL "${PIDS[@]}") >/dev/null 2>&1 &
  local watchdog=$!
  for pid in "${PIDS[@]}"; do wait "$pid" 2>/dev/null; done
  kill "$watchdog" 2>/dev/null
  for ns in "$LAN" "$INS" "${HOSTS[@]}"; do ip netns del "$ns" 2>/dev/null; done
  if [ $code -ne 0 ] && [ $code -ne 77 ] && [ -n "$WORK" ]; then
    for f in "$WORK"/*.log; do echo "---- $(basename "$f") (last 15 lines)"; tail -15 "$f"; done
  fi
  [ -n "$WORK" ] && rm -rf "$WORK"
  exit $code
}
trap cleanup EXIT
trap 'exit 1' INT TERM

fail() { echo "FAIL: $*"; exit 1; }

# ---- the LAN: a bridge, one veth per host, eth0 inside it ----------------
ip -n "$LAN" link add br0 type bridge mcast_snooping 0 || fail "cannot create a bridge"
ip -n "$LAN" link set br0 up
add_host() {  # NS ADDRESS
  local ns=$1 addr=$2 port=p${#PORTS[@]}
  PORTS+=("$port")
  ip netns add "$ns" || fail "cannot create namespace $ns"
  ip -n "$LAN" link add "$port" type veth peer name eth0 netns "$ns" || fail "cannot create a veth pair for $ns"
  ip -n "$LAN" link set "$port" master br0 up
  ip -n "$ns" link set lo up
  ip -n "$ns" addr add "$addr/24" dev eth0
  ip -n "$ns" link set eth0 up
  # LCM's multicast leaves by the route to 224.0.0.0/4 (README "A classroom on a LAN").
  ip -n "$ns" route add 224.0.0.0/4 dev eth0
}
PORTS=()
add_host "$INS" 10.76.0.1
for i in 0 1 2; do add_host "${HOSTS[$i]}" "10.76.0.1$i"; done

# ---- the processes -------------------------------------------------------
KEY=$WORK/instructor.key
"$BIN/rise-instructor" keygen "$KEY" >/dev/null || fail "rise-instructor keygen"
PANEL=$SRC/panels/definitions/rise_console.yaml
printf '0.0 mode drive\n0.0 speed medium\n0.2 deadman pressed\n' >"$WORK/console.txt"
cat >"$WORK/task.yaml" <<EOF
task: classroom
robot: $SRC/sim/robots/skid4.yaml
world: $SRC/sim/worlds/yard.yaml
panel: $PANEL
time_limit_s: 100000
events:
  - {name: bump, kind: collision, points: -1}
EOF

start() {  # NS HOSTNAME LOG [VAR=VALUE...] PROGRAM ARGS...: started in NS under its own host name, its pid kept
  local ns=$1 name=$2 logf=$3; shift 3
  ip netns exec "$ns" unshare --uts -- sh -c 'hostname "$0" && exec env "$@"' "$name" "$@" >"$WORK/$logf.log" 2>&1 &
  PIDS+=($!)
}

for i in 0 1 2; do
  ns=${HOSTS[$i]} id=${IDS[$i]} name=station-${LETTERS[$i]}
  clock=()
  # Station B: a host whose wall clock is SKEW_S ahead (steady clock untouched).
  [ $i -eq 1 ] && clock=(LD_PRELOAD="$FAKETIME_LIB" FAKETIME="+${SKEW_S}s" FAKETIME_DONT_FAKE_MONOTONIC=1)
  start "$ns" "$name" "$id.emulator" "${clock[@]}" "$BIN/rise-panel" emulate --panel "$PANEL" \
    --can socketcand+listen://127.0.0.1:29536/can0 --script "$WORK/console.txt" --hold
  start "$ns" "$name" "$id.hild" "${clock[@]}" "$BIN/rise-hild" --panel "$PANEL" --can socketcand://127.0.0.1:29536/can0 \
    --id "$id" --lcm "$LCM" --instructor-key "$KEY"
  start "$ns" "$name" "$id.sim" "${clock[@]}" "$BIN/rise-sim" --id "$id" --lcm "$LCM" --panel-timeout-ms "$PANEL_TIMEOUT_MS" \
    --instructor-key "$KEY"
  start "$ns" "$name" "$id.trainer" "${clock[@]}" "$BIN/rise-trainer" run-task "$WORK/task.yaml" --id "$id" --lcm "$LCM" \
    --out "$WORK/reports/$id"
done
start "$INS" instructor instructor "$BIN/rise-instructor" serve --listen "127.0.0.1:$PORT" --token "$TOKEN" --lcm "$LCM" \
  --instructor-key "$KEY" --world "$SRC/sim/worlds/yard.yaml" --lost-after-ms "$LOST_AFTER_MS" --push-hz 20
# Its first log line comes once it listens: the page and the API are asked after it.
wait_line "$WORK/instructor.log" 'rise-instructor serve: http' 20 >/dev/null ||
  fail "rise-instructor serve did not start listening: $(tail -n 5 "$WORK/instructor.log")"

# ---- the console page, watching station C's row (loaded while the stations start)
WEB=$SRC/instructor/web
PAGE=0
if [ -x /usr/bin/chromium ] && [ -d "$WEB/node_modules/playwright-core" ] && command -v node >/dev/null; then
  PAGE=1
  ip netns exec "$INS" node "$SRC/tests/classroom/console_link_check.cjs" "http://127.0.0.1:$PORT" "$TOKEN" \
    "${IDS[2]}" "$WEB" >"$WORK/page.log" 2>&1 &
  PIDS+=($!)
else
  log "no page check: needs /usr/bin/chromium, node and instructor/web/node_modules (run.sh's web_setup)"
fi

api() {  # PATH [curl args...]: the instructor's API, from its namespace
  local path=$1; shift
  ip netns exec "$INS" curl -s -m 2 -H "X-Rise-Token: $TOKEN" "$@" "http://127.0.0.1:$PORT$path"
}
trainees() { api /api/trainees; }
# jq over /api/trainees until it is true, for at most $1 ms; false when it
# never was. Asked again at each push of the console's stream (/api/stream,
# --push-hz 20: when the server has news, at least once a second).
wait_for() {
  local limit_ms=$1 filter=$2 line
  trainees | jq -e "$filter" >/dev/null 2>&1 && return 0
  while read -r line; do
    [[ $line == data:* ]] || continue
    trainees | jq -e "$filter" >/dev/null 2>&1 && return 0
  done < <(ip netns exec "$INS" curl -sN -m "$((limit_ms / 1000)).$(printf %03d $((limit_ms % 1000)))" \
             -H "X-Rise-Token: $TOKEN" "http://127.0.0.1:$PORT/api/stream")
  trainees | jq -e "$filter" >/dev/null 2>&1
}
link_of() { trainees | jq -c --arg id "$1" '.[] | select(.id == $id) | .link'; }

# ---- 1. every trainee listed, live, with its clock measured ----------------
log "waiting for the instructor to list ${IDS[*]}"
every_live='[.[] | select(.link.state == "live" and .panel_state and .robot_state and .task_status
                          and (.link.clock_offset_ms != null))] | length'
wait_for 40000 "($every_live) >= 3 and ([.[].id] | contains([\"${IDS[0]}\", \"${IDS[1]}\", \"${IDS[2]}\"]))" ||
  fail "the instructor does not list all three trainees live with their clocks measured: $(trainees | jq -c '[.[] | {id, link}]')"
# More probes until every offset has settled near its truth (the filter keeps
# the least delayed); the checks below say which one did not.
settled="[.[] | select(.id == \"${IDS[0]}\" or .id == \"${IDS[2]}\") | .link.clock_offset_ms | fabs < 100] + [.[] | select(.id == \"${IDS[1]}\") | (.link.clock_offset_ms - $((SKEW_S * 1000)) | fabs) < 100] | all and length == 3"
wait_for 10000 "$settled" || log "clock offsets not settled within 10 s"
T=$(trainees)
for i in 0 1 2; do
  id=${IDS[$i]}
  L=$(jq -c --arg id "$id" '.[] | select(.id == $id) | .link' <<<"$T")
  log "$id: $L"
  want=0
  [ $i -eq 1 ] && want=$((SKEW_S * 1000))
  jq -e --argjson want $want '(.clock_offset_ms - $want | fabs) < 100' <<<"$L" >/dev/null ||
    fail "$id: clock offset $(jq .clock_offset_ms <<<"$L") ms, expected $want ± 100 ms"
  jq -e '.state == "live" and (.arrival_age_ms | fabs) < 500' <<<"$L" >/dev/null ||
    fail "$id: not judged fresh: $L"
  jq -e --arg host "station-${LETTERS[$i]}" '.clock_host == $host' <<<"$L" >/dev/null ||
    fail "$id: clock measured on $(jq .clock_host <<<"$L"), not station-${LETTERS[$i]}"
done

if [ $PAGE -eq 1 ]; then
  # Software WebGL on a busy machine: the page may take a while to load.
  wait_line "$WORK/page.log" '^(READY|RESULT)' 60 >/dev/null
  grep -q '^READY' "$WORK/page.log" || fail "the console page did not show ${IDS[2]} live: $(cat "$WORK/page.log")"
  log "the console page shows ${IDS[2]} live"
fi

# ---- 2. a fault into B; A and C untouched ------------------------------------
seq_of() { jq --arg id "$1" '.[] | select(.id == $id) | .panel_state.seq' <<<"$2"; }
T=$(trainees)
SEQ_A=$(seq_of "${IDS[0]}" "$T") SEQ_C=$(seq_of "${IDS[2]}" "$T")
R=$(api /api/fault/inject -X POST -H 'Content-Type: application/json' -d "{\"trainee\": \"${IDS[1]}\", \"fault\": \"stick-stuck\"}")
log "inject into ${IDS[1]}: $R"
wait_for 3000 ".[] | select(.id == \"${IDS[1]}\") | .panel_state.active_faults | any(startswith(\"stick-stuck:\"))" ||
  fail "${IDS[1]}: the signed fault did not apply: $(trainees | jq -c ".[] | select(.id == \"${IDS[1]}\") | .panel_state.active_faults")"
# A and C published 50 states (0.5 s) after the inject: none of them may carry it.
wait_for 5000 "[.[] | select((.id == \"${IDS[0]}\" and .panel_state.seq > $SEQ_A + 50) or
                            (.id == \"${IDS[2]}\" and .panel_state.seq > $SEQ_C + 50))] | length == 2" ||
  fail "${IDS[0]} and ${IDS[2]} did not publish 50 states after the inject"
T=$(trainees)
for id in "${IDS[0]}" "${IDS[2]}"; do
  jq -e --arg id "$id" '.[] | select(.id == $id) | (.panel_state.active_faults | length) == 0 and
                        (.robot_state.active_faults | length) == 0' <<<"$T" >/dev/null ||
    fail "$id has an active fault: $(jq -c --arg id "$id" '.[] | select(.id == $id) | .panel_state.active_faults' <<<"$T")"
done
jq -e '[.[].panel_state.active_faults[] | select(startswith("command_rejected"))] | length == 0' <<<"$T" >/dev/null ||
  fail "a command was rejected: $(jq -c '[.[].panel_state.active_faults[]]' <<<"$T")"
log "the fault applies on ${IDS[1]} ($(jq -c ".[] | select(.id == \"${IDS[1]}\") | .panel_state.active_faults" <<<"$T")); ${IDS[0]} and ${IDS[2]} have none"

# rise-instructor inject measures B's clock itself (3 probes) and stamps its command so.
OUT=$(ip netns exec "$INS" "$BIN/rise-instructor" inject --lcm "$LCM" --instructor-key "$KEY" --trainee "${IDS[1]}" \
  offset drive_x --value 0.2 --id cli-offset --confirm 5 2>&1) || fail "rise-instructor inject into ${IDS[1]}: $OUT"
grep -q "cli-offset on ${IDS[1]}: confirmed" <<<"$OUT" || fail "rise-instructor inject into ${IDS[1]}: $OUT"
log "rise-instructor inject: $(grep -o "${IDS[1]}'s clock.*" <<<"$OUT"); $(tail -1 <<<"$OUT")"

# ---- 3. C's link cut ------------------------------------------------------------
C=${IDS[2]}
# rise-instructor list, listening across the cut: C heard, then silent.
ip netns exec "$INS" "$BIN/rise-instructor" list --lcm "$LCM" --wait 1.5 >"$WORK/list.log" 2>&1 &
LIST=$!
PIDS+=($LIST)
wait_line "$WORK/list.log" "hearing $C\$" 5 >/dev/null || fail "rise-instructor list did not hear $C: $(cat "$WORK/list.log")"
CUT=$(now_ms)
ip -n "${HOSTS[2]}" link set eth0 down
wait_for 3000 ".[] | select(.id == \"$C\") | .link.state == \"lost\"" || fail "$C not lost 3 s after its link was cut"
LOST_MS=$(($(now_ms) - CUT))
log "$C lost on /api/trainees after $LOST_MS ms"
[ $LOST_MS -le 1000 ] || fail "$C shown lost after $LOST_MS ms (bound 1000 ms)"
T=$(trainees)
for id in "${IDS[0]}" "${IDS[1]}"; do
  jq -e --arg id "$id" '.[] | select(.id == $id) | .link.state == "live"' <<<"$T" >/dev/null ||
    fail "$id not live while $C is cut: $(jq -c --arg id "$id" '.[] | select(.id == $id) | .link' <<<"$T")"
done
# rise-sim's view: its PanelState stopped coming (spdlog stamps the line, ms).
stopped_at() {  # LOG: the ms epoch of the first "motors stopped: no panel state" line after CUT (within 5 s)
  local t line code=1
  follow "$1" 5
  while read -r line; do
    [[ $line == *"motors stopped: no panel state"* ]] || continue
    t=$(date -d "$(sed -E 's/^\[([^]]+)\].*/\1/' <<<"$line")" +%s%3N)
    [ "$t" -ge "$CUT" ] && { echo "$t"; code=0; break; }
  done <&"$FOLLOW_FD"
  unfollow
  return $code
}
STOP_AT=$(stopped_at "$WORK/$C.sim.log") || fail "$C's rise-sim did not stop its robot for lack of PanelState"
STOP_MS=$((STOP_AT - CUT))
log "$C's rise-sim stopped the robot (no panel state) $STOP_MS ms after the cut"
[ $STOP_MS -le $((PANEL_TIMEOUT_MS + 60)) ] ||
  fail "$C's rise-sim stopped $STOP_MS ms after the cut (panel timeout $PANEL_TIMEOUT_MS ms + 60 ms)"

wait $LIST || fail "rise-instructor list: $(cat "$WORK/list.log")"
grep -q "LOST: nothing from rise/$C/\*" "$WORK/list.log" || fail "rise-instructor list does not show $C lost: $(cat "$WORK/list.log")"
for id in "${IDS[0]}" "${IDS[1]}"; do
  grep -q "^$id " "$WORK/list.log" || fail "rise-instructor list misses $id: $(cat "$WORK/list.log")"
  ! grep -q "LOST: nothing from rise/$id/" "$WORK/list.log" || fail "rise-instructor list shows $id lost: $(cat "$WORK/list.log")"
done
log "rise-instructor list: $(grep LOST "$WORK/list.log")"
# C stays lost while its link is down (2 s in all: a hold, no peer to wait on).
LEFT_MS=$((CUT + 2000 - $(now_ms)))
[ $LEFT_MS -gt 0 ] && sleep "$((LEFT_MS / 1000)).$(printf %03d $((LEFT_MS % 1000)))"
link_of "$C" | jq -e '.state == "lost"' >/dev/null || fail "$C not lost 2 s into the cut: $(link_of "$C")"

# ---- 4. C's link back -------------------------------------------------------------
BACK=$(now_ms)
ip -n "${HOSTS[2]}" link set eth0 up
ip -n "${HOSTS[2]}" route replace 224.0.0.0/4 dev eth0
wait_for 5000 ".[] | select(.id == \"$C\") | .link.state == \"live\" and (.panel_state.failsafe == false or .panel_state.failsafe == 0)" ||
  fail "$C not live again 5 s after its link came back: $(trainees | jq -c ".[] | select(.id == \"$C\") | {link, failsafe: .panel_state.failsafe, reason: .panel_state.failsafe_reason}")"
log "$C live again $(($(now_ms) - BACK)) ms after its link came back"
wait_line "$WORK/$C.sim.log" 'motors enabled' 5 2 >/dev/null || fail "$C's rise-sim did not enable its motors again"

if [ $PAGE -eq 1 ]; then
  wait_line "$WORK/page.log" '^RESULT' 30 >/dev/null
  RES=$(sed -n 's/^RESULT //p' "$WORK/page.log")
  [ -n "$RES" ] || fail "the page check gave no result: $(cat "$WORK/page.log")"
  jq -e '.error | not' <<<"$RES" >/dev/null || fail "the page check: $(jq -r .error <<<"$RES")"
  PAGE_LOST_MS=$(($(jq .lost_at_ms <<<"$RES") - CUT))
  log "the console page: $C lost $PAGE_LOST_MS ms after the cut, live $(($(jq .live_at_ms <<<"$RES") - BACK)) ms after the link came back ($(jq -c '{lost_row, lost_option, live_row}' <<<"$RES"))"
  [ $PAGE_LOST_MS -le 1000 ] || fail "the console page showed $C lost after $PAGE_LOST_MS ms (bound 1000 ms)"
  jq -e '(.lost_option | endswith("(lost)")) and (.lost_row | startswith("LOST")) and .live_row == "live" and (.live_option | endswith("(lost)") | not)' \
    <<<"$RES" >/dev/null || fail "the console page: $RES"
fi
log "PASS"
