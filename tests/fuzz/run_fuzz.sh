#!/usr/bin/env bash
# Builds one libFuzzer target with clang and runs it for a bounded number of
# inputs from a seed corpus this script writes itself (nothing binary is kept
# in the repository).
#   run_fuzz.sh CLANGXX ROOT WORKDIR TARGET RUNS
# TARGET is console_can, dbc or hid_descriptor; sources are tests/fuzz/TARGET_fuzz.cpp plus the
# library sources it needs. Crash inputs land in WORKDIR/TARGET-artifacts/.
set -euo pipefail
clangxx=$1 root=$2 work=$3 target=$4 runs=$5

case "$target" in
  console_can) sources=("$root/firmware_protocol/console_can.cpp") ;;
  console_modbus) sources=("$root"/firmware_protocol/console_{can,modbus}.cpp) ;;
  dbc) sources=("$root/firmware_protocol/dbc.cpp") ;;
  hid_descriptor) sources=("$root"/firmware_protocol/hid_{descriptor,report,text}.cpp) ;;
  *) echo "run_fuzz.sh: unknown target $target" >&2; exit 2 ;;
esac
sources+=("$root/tests/fuzz/${target}_fuzz.cpp")
binary="$work/${target}_fuzz"
mkdir -p "$work"

# Rebuild only when a source or header is newer than the binary.
rebuild=0
[ -x "$binary" ] || rebuild=1
for f in "${sources[@]}" "$root"/firmware_protocol/*.hpp; do
  [ "$f" -nt "$binary" ] && rebuild=1
done
if [ $rebuild -eq 1 ]; then
  echo "run_fuzz.sh: compiling $binary"
  "$clangxx" -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
    -I"$root" "${sources[@]}" -o "$binary.tmp"
  mv "$binary.tmp" "$binary"
fi

# A fresh corpus every run, so the bounded run is reproducible with -seed=1.
corpus="$work/${target}-corpus"
artifacts="$work/${target}-artifacts"
rm -rf "$corpus"
mkdir -p "$corpus" "$artifacts"
extra=()
case "$target" in
  console_can)
    # Node 1 (max delta 1): the README's worked examples, a repeat, a bad CRC,
    # a short frame, a reset, and the Axes0 frame again after the reset.
    printf '\x11\x11\x01\x08\xB0\x03\x00\x40\x00\xE0\x00\x00' >"$corpus/axes"
    printf '\x11\x31\x01\x08\xCA\x03\x21\x00\x02\x00\x00\x00\x31\x01\x08\xCA\x03\x21\x00\x02\x00\x00\x00' >"$corpus/buttons-repeat"
    printf '\x01\x31\x01\x08\xCB\x03\x21\x00\x02\x00\x00\x00\x31\x01\x05\xCA\x03\x21\x00\x02' >"$corpus/bad"
    printf '\x01\x11\x01\x08\xB0\x03\x00\x40\x00\xE0\x00\x00\x00\x00\xFF\x11\x01\x08\xB0\x03\x00\x40\x00\xE0\x00\x00' >"$corpus/reset"
    ;;
  console_modbus)
    # The README's worked example (registers, buttons, last counter 2) and
    # the same block with a torn CRC; then a feedback block (LED 0, beep,
    # display 0 = 1.25).
    ex='\x40\x00\xE0\x00\x00\x00\x00\x00\x00\x00\x80\x00\x00\x01\x00\x00\x00\xFF\x00\x00\x00\x00\x00\x00\x00\x01\x00\x01\x00\x01\x11\x70\x00\x03'
    fb='\x01\x00\x00\x00\x00\x02\x00\x02\x00\x00\x00\x7D'
    printf "$ex"'\xB6\x07\x21\x00\x02\x00\x01\x00\x02'"$fb" >"$corpus/example"
    printf "$ex"'\xB6\x08\x21\x00\x02\x00\x00'"$fb" >"$corpus/torn"
    ;;
  dbc)
    cp "$root/firmware_protocol/console_can_v1.dbc" "$corpus/console_can_v1.dbc"
    if [ -n "${RISE_TEST_DATA:-}" ] && [ -d "$RISE_TEST_DATA/can" ]; then
      find "$RISE_TEST_DATA/can" -name '*.dbc' -size -20k -exec cp {} "$corpus/" \;
    fi
    printf 'VERSION ""\nBO_ 2147483905 Ext: 8 N\n SG_ Mux M : 0|8@1+ (1,0) [0|0] "" N\n SG_ A m1 : 15|12@0- (0.5,-3) [0|0] "u" N\nVAL_ 2147483905 A -1 "minus" ;\nSIG_VALTYPE_ 2147483905 A : 0;\n' >"$corpus/seed.dbc"
    extra=(-dict="$root/tests/fuzz/dbc.dict")
    ;;
  hid_descriptor)
    # Gravis GamePad Pro (Android CTS) as bytes, the hid-recorder descriptors
    # of the test data as bytes, and the text files as they are.
    printf '\x05\x01\x09\x05\xa1\x01\x05\x01\x09\x01\xa1\x00\x09\x30\x09\x31\x15\x00\x26\xff\x00\x75\x08\x95\x02\x81\x02\xc0\x05\x09\x19\x01\x29\x0a\x15\x00\x25\x01\x75\x01\x95\x0a\x81\x02\x95\x01\x75\x06\x81\x01\xc0' >"$corpus/gravis"
    if [ -n "${RISE_TEST_DATA:-}" ] && [ -d "$RISE_TEST_DATA/hid" ]; then
      for f in "$RISE_TEST_DATA"/hid/*.hid; do
        printf "$(grep '^R:' "$f" | cut -d' ' -f3- | sed -E 's/([0-9a-fA-F]{2}) ?/\\x\1/g')" >"$corpus/$(basename "$f").bin"
      done
      find "$RISE_TEST_DATA/hid" -type f -size -20k -exec cp {} "$corpus/" \;
    fi
    ;;
esac

cd "$work"
exec "$binary" -runs="$runs" -seed=1 -max_total_time=50 -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 -artifact_prefix="$artifacts/" "${extra[@]}" "$corpus"
