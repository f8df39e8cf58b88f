#!/usr/bin/env bash
# run_in_vcan_vm.sh - runs one program inside a throw-away qemu VM whose kernel
# has a real Linux CAN stack, and exits with the program's exit code.
#
# Why: the kernels of this machine and of CI have no AF_CAN (socket(PF_CAN)
# fails with EAFNOSUPPORT) and no usable KVM, so socketcan:// could never meet
# a CAN stack. Debian's own kernel (linux-image-amd64) has every CAN module;
# qemu boots it with software emulation (TCG) from a small initramfs:
#   - static busybox as /bin/*, the modules can, can-raw and vcan with their
#     dependencies (modules.dep), and an /init that creates the interfaces
#       vcan0  mtu 72 (CAN FD)        vcan1  mtu 16 (classic CAN only)
#     then runs the program as root in /tmp, stdin /dev/null;
#   - the program, each --extra FILE, and every library ldd lists for them,
#     each at its host path (RUNPATH and $ORIGIN keep working).
# The busybox/modules/init part and the uncompressed kernel are built once and
# cached; only the program's part is packed per run.
#
# Usage: run_in_vcan_vm.sh [--extra FILE]... [--timeout SEC] PROGRAM [ARGS...]
#   --extra FILE   also put FILE (or a directory) into the VM, e.g. can-utils'
#                  /usr/bin/cansend; a bare name is looked up in PATH
#   --timeout SEC  hard wall-clock limit for the VM (default 240)
# Inside the VM, busybox applets (ip, cat, ...) are found in PATH; a file of the
# same name given with --extra must be called by its full path.
#
# Output: the program's stdout and stderr go to a serial port of their own
# (ttyS2, not a tty for the program) that qemu writes to a host file, printed
# here when the VM has ended, so kernel messages never mix into it. The kernel
# console (ttyS0) is printed only when the VM set-up failed or timed out (or
# with RISE_VCAN_VERBOSE=1). The exit code comes back on ttyS1.
#
# Exit status: the program's (128+N when signal N killed it), or
#   77   a prerequisite is missing (qemu, kernel image and modules, busybox,
#        cpio, an --extra file): ctest's SKIP_RETURN_CODE
#   124  the VM ran past --timeout
#   125  set-up failure (bad usage, unresolved library, VM set-up, no result)
#
# Environment:
#   RISE_VCAN_CACHE    cache dir (default ${XDG_CACHE_HOME:-$HOME/.cache}/rise-vcan)
#   RISE_VCAN_KERNEL   kernel image (default: newest /boot/vmlinuz-*)
#   RISE_VCAN_ACCEL    tcg (default) or kvm; the /dev/kvm of sandboxes often
#                      exists but cannot run guests, so KVM is opt-in
#   RISE_VCAN_VERBOSE  1: print the kernel console and keep the work dir
#
# Host packages (Debian 12, --no-install-recommends): qemu-system-x86
# linux-image-amd64 busybox-static cpio (+ can-utils for the peers).
set -Eeuo pipefail

log() { echo "rise-vcan: $*" >&2; }
skip() { log "SKIP: $*"; exit 77; }
die() { log "error: $*"; exit 125; }
trap 'log "error: \"$BASH_COMMAND\" failed (line $LINENO)"; exit 125' ERR
now_ms() { date +%s%3N; }
T_START=$(now_ms)

# --------------------------------------------------------------- arguments ---
EXTRAS=()
TIMEOUT_S=240
while [ $# -gt 0 ]; do
  case "$1" in
    --extra)   [ $# -ge 2 ] || die "--extra needs a file"; EXTRAS+=("$2"); shift 2 ;;
    --timeout) [ $# -ge 2 ] || die "--timeout needs seconds"; TIMEOUT_S=$2; shift 2 ;;
    -h|--help) sed -n '2,/^set -Eeuo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    --)        shift; break ;;
    -*)        die "unknown option $1 (see --help)" ;;
    *)         break ;;
  esac
done
[ $# -ge 1 ] || die "no program given (see --help)"
[[ "$TIMEOUT_S" =~ ^[1-9][0-9]*$ ]] || die "--timeout wants whole seconds, got '$TIMEOUT_S'"

# abs_path NAME_OR_PATH: absolute host path (a bare name through PATH), or fails.
abs_path() {
  local p=$1
  case "$p" in */*) ;; *) p=$(command -v -- "$p") || return 1 ;; esac
  [ -e "$p" ] || return 1
  echo "$(cd "$(dirname -- "$p")" && pwd)/$(basename -- "$p")"
}
PROGRAM=$(abs_path "$1") || die "program '$1' not found"
shift
EXTRA_PATHS=()
for f in ${EXTRAS[@]+"${EXTRAS[@]}"}; do
  p=$(abs_path "$f") || skip "--extra '$f' not found (can-utils not installed?)"
  EXTRA_PATHS+=("$p")
done

# ----------------------------------------------------------- prerequisites ---
command -v qemu-system-x86_64 >/dev/null ||
  skip "qemu-system-x86_64 not found (apt-get install --no-install-recommends qemu-system-x86)"
KERNEL=${RISE_VCAN_KERNEL:-$(ls -1 /boot/vmlinuz-* 2>/dev/null | sort -V | tail -n 1)}
[ -n "$KERNEL" ] && [ -r "$KERNEL" ] ||
  skip "no readable kernel image /boot/vmlinuz-* (apt-get install --no-install-recommends linux-image-amd64)"
KVER=$(basename -- "$KERNEL"); KVER=${KVER#vmlinuz-}
MODDIR=/lib/modules/$KVER
[ -r "$MODDIR/modules.dep" ] || skip "no $MODDIR/modules.dep for kernel $KERNEL"
BUSYBOX=$(command -v busybox) || skip "busybox not found (apt-get install busybox-static)"
! ldd "$BUSYBOX" >/dev/null 2>&1 || skip "$BUSYBOX is not static (apt-get install busybox-static)"
command -v cpio >/dev/null || skip "cpio not found (apt-get install cpio)"

CACHE=${RISE_VCAN_CACHE:-${XDG_CACHE_HOME:-${HOME:-/tmp}/.cache}/rise-vcan}
mkdir -p "$CACHE"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/rise-vcan.XXXXXX")
QEMU_PID=""
cleanup() {
  [ -z "$QEMU_PID" ] || kill -TERM "$QEMU_PID" 2>/dev/null || true
  if [ "${RISE_VCAN_VERBOSE:-0}" = 1 ]; then log "work dir kept: $WORK"; else rm -rf "$WORK"; fi
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# pack DIR OUT: an uncompressed newc cpio archive of DIR, every file owned by
# root. Uncompressed, because under TCG the guest would spend longer
# inflating than qemu spends copying; the kernel takes a series of archives.
pack() { (cd "$1" && find . -print0 | LC_ALL=C sort -z | cpio --null -o -H newc -R 0:0 --quiet) > "$2"; }

# ----------------------------------------------------- cached: the kernel ---
# A bzImage inflates itself inside the guest, ~4 s under TCG for Debian's
# XZ-packed kernel. qemu can instead start the ELF vmlinux through its PVH
# entry point (CONFIG_PVH=y on Debian), so inflate it once on the host.
extract_vmlinux() {  # extract_vmlinux BZIMAGE OUT: first payload that inflates to ELF
  local spec magic cmd off
  for spec in 'fd377a585a00:xz -dcq --single-stream' '28b52ffd:zstd -dcq' '1f8b0800:gzip -dcq'; do
    magic=$(echo "${spec%%:*}" | sed 's/../\\x&/g'); cmd=${spec#*:}
    command -v "${cmd%% *}" >/dev/null || continue
    for off in $(LC_ALL=C grep -obUaP "$magic" "$1" | awk -F: 'NR <= 4 { print $1 }'); do
      tail -c +$((off + 1)) "$1" | $cmd > "$2" 2>/dev/null || true
      [ "$(head -c 4 "$2" | od -An -tx1 | tr -d ' \n')" != 7f454c46 ] || return 0
    done
  done
  return 1
}
BOOT_KERNEL=$KERNEL
if grep -qs '^CONFIG_PVH=y' "/boot/config-$KVER"; then
  VMLINUX=$CACHE/vmlinux-$KVER-$(stat -Lc '%s-%Y' "$KERNEL")
  if [ ! -s "$VMLINUX" ]; then
    if extract_vmlinux "$KERNEL" "$VMLINUX.$$"; then
      mv -f "$VMLINUX.$$" "$VMLINUX"  # atomic: parallel runs may race here
      find "$CACHE" -maxdepth 1 -name 'vmlinux-*' ! -name "${VMLINUX##*/}" -delete  # 60+ MiB each
    else
      rm -f "$VMLINUX.$$"; log "could not inflate $KERNEL: booting it as is (slower)"
    fi
  fi
  [ ! -s "$VMLINUX" ] || BOOT_KERNEL=$VMLINUX
fi

# ------------------------------------------- cached: busybox, modules, init ---
# /init runs as PID 1 and must never return (that panics the kernel). It ends
# the VM with "reboot -f", which qemu's -no-reboot turns into an exit;
# "poweroff -f" without ACPI would only halt the CPU until the timeout.
INIT_SCRIPT='#!/bin/sh
/bin/busybox --install -s /bin
export PATH=/usr/local/bin:/usr/bin:/usr/sbin:/bin:/sbin HOME=/tmp
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
finish() {
  echo "RISE_VCAN_EXIT=$1" > /dev/ttyS1
  reboot -f
  sleep 60
}
setup_failed() { echo "rise-vcan: guest set-up failed: $*"; dmesg | tail -n 20; finish 125; }
for m in $(cat /etc/rise-vcan/modules); do insmod "$m" || setup_failed "insmod $m"; done
ip link set lo up
ip link add dev vcan0 type vcan && ip link set dev vcan0 mtu 72 && ip link set dev vcan0 up ||
  setup_failed "vcan0"
ip link add dev vcan1 type vcan && ip link set dev vcan1 mtu 16 && ip link set dev vcan1 up ||
  setup_failed "vcan1"
# Raw mode: the host file gets the bytes as written, without CR before LF.
stty -F /dev/ttyS2 raw -echo || setup_failed "stty ttyS2"
. /etc/rise-vcan/cmd
cd /tmp
# Through cat, so that the program writes to a pipe, not a tty (no colours);
# the last close of ttyS2 waits until the UART has sent everything.
{ "$@" < /dev/null 2>&1; echo $? > /tmp/rc; } | cat > /dev/ttyS2
finish "$(cat /tmp/rc)"
'
# RISE_VCAN_EXTRA_MODULES adds modules (and their dependencies), e.g. "hid uhid hid-generic".
MODULES="can can-raw vcan${RISE_VCAN_EXTRA_MODULES:+ $RISE_VCAN_EXTRA_MODULES}"
BASE_KEY=$( { echo "$INIT_SCRIPT$MODULES$KVER"; stat -Lc '%s %Y' "$KERNEL" "$BUSYBOX" "$MODDIR/modules.dep"; } |
  sha256sum | cut -c1-16)
BASE=$CACHE/base-$KVER-$BASE_KEY.cpio
if [ ! -s "$BASE" ]; then
  ROOT=$WORK/base
  mkdir -p "$ROOT"/{bin,dev,proc,sys,tmp,etc/rise-vcan}
  cp "$BUSYBOX" "$ROOT/bin/busybox"
  ln -s busybox "$ROOT/bin/sh"
  printf '%s' "$INIT_SCRIPT" > "$ROOT/init"
  chmod 755 "$ROOT/init"
  declare -A ADDED=()
  add_module() {  # add_module RELPATH: its dependencies first, then itself
    local rel=$1 dep
    [ -z "${ADDED[$rel]:-}" ] || return 0
    ADDED[$rel]=1
    for dep in $(awk -F: -v r="$rel" '$1 == r { print $2 }' "$MODDIR/modules.dep"); do
      add_module "$dep"
    done
    mkdir -p "$ROOT/lib/modules/$KVER/$(dirname "$rel")"
    case "$rel" in  # busybox insmod cannot be relied on to inflate modules
      *.xz)  xz -dc "$MODDIR/$rel" > "$ROOT/lib/modules/$KVER/${rel%.xz}"; rel=${rel%.xz} ;;
      *.zst) zstd -qdc "$MODDIR/$rel" > "$ROOT/lib/modules/$KVER/${rel%.zst}"; rel=${rel%.zst} ;;
      *)     cp "$MODDIR/$rel" "$ROOT/lib/modules/$KVER/$rel" ;;
    esac
    echo "/lib/modules/$KVER/$rel" >> "$ROOT/etc/rise-vcan/modules"
  }
  for m in $MODULES; do
    rel=$(awk -F: -v n="$m" '{ f = $1; sub(".*/", "", f); sub(/\.ko(\.(xz|zst))?$/, "", f) }
                             f == n { print $1; exit }' "$MODDIR/modules.dep")
    [ -n "$rel" ] || skip "kernel $KVER has no module $m"
    add_module "$rel"
  done
  pack "$ROOT" "$BASE.$$"
  mv -f "$BASE.$$" "$BASE"
  find "$CACHE" -maxdepth 1 -name 'base-*.cpio' ! -name "${BASE##*/}" -delete
fi

# ------------------------------------------------ per run: the program ---
ROOT=$WORK/run
mkdir -p "$ROOT/etc/rise-vcan"
# put HOSTPATH: copy it to the same path in the VM; an ELF file brings every
# library ldd resolves (and the loader). dlopen()ed libraries need --extra.
put() {
  local src=$1 out lib
  [ ! -e "$ROOT$src" ] || return 0
  mkdir -p "$ROOT$(dirname -- "$src")"
  if [ -d "$src" ]; then cp -rL -- "$src" "$ROOT$src"; return 0; fi
  cp -L -- "$src" "$ROOT$src"
  # The guest keeps its files in its 512 MB of RAM: debug info (most of a
  # RelWithDebInfo test program) would fill it. Not an ELF file: left as it is.
  strip --strip-debug -- "$ROOT$src" 2>/dev/null || true
  out=$(ldd -- "$src" 2>/dev/null) || return 0  # static binary or script
  ! grep -q 'not found' <<<"$out" || die "$src: unresolved libraries:"$'\n'"$out"
  for lib in $(awk '/=> \// { print $3 } /^[[:space:]]*\// { print $1 }' <<<"$out"); do
    put "$lib"
  done
}
put "$PROGRAM"
for p in ${EXTRA_PATHS[@]+"${EXTRA_PATHS[@]}"}; do put "$p"; done
shq() { printf "'%s'" "$(printf '%s' "$1" | sed "s/'/'\\\\''/g")"; }
{
  printf 'set -- %s' "$(shq "$PROGRAM")"
  for a in "$@"; do printf ' %s' "$(shq "$a")"; done
  echo
} > "$ROOT/etc/rise-vcan/cmd"
pack "$ROOT" "$WORK/run.cpio"
cat "$BASE" "$WORK/run.cpio" > "$WORK/initramfs.cpio"
T_PACKED=$(now_ms)

# --------------------------------------------------------------- the VM ---
case "${RISE_VCAN_ACCEL:-tcg}" in
  tcg) ACCEL=(-accel tcg) ;;
  kvm) ACCEL=(-accel kvm -cpu host) ;;
  *)   die "RISE_VCAN_ACCEL must be tcg or kvm" ;;
esac
# The parameters after "quiet" only shorten the boot of a throw-away guest:
# no CPU-bug mitigations, crypto self-tests, TSC and timer checks, audit.
APPEND="console=ttyS0 panic=-1 oops=panic quiet loglevel=3 mitigations=off"
APPEND="$APPEND cryptomgr.notests tsc=reliable no_timer_check nowatchdog audit=0 init_on_alloc=0"
# "pc", not "microvm": microvm hung on ~30% of boots under TCG.
timeout --kill-after=5 "$TIMEOUT_S" qemu-system-x86_64 \
  -nodefaults -no-user-config -machine pc "${ACCEL[@]}" -smp 1 -m 512 \
  -display none -monitor none -no-reboot \
  -kernel "$BOOT_KERNEL" -initrd "$WORK/initramfs.cpio" -append "$APPEND" \
  -serial "file:$WORK/console" -serial "file:$WORK/result" -serial "file:$WORK/output" \
  < /dev/null > "$WORK/qemu.log" 2>&1 &
QEMU_PID=$!
QEMU_RC=0
wait "$QEMU_PID" || QEMU_RC=$?
QEMU_PID=""
T_END=$(now_ms)

[ ! -s "$WORK/output" ] || tr -d '\r' < "$WORK/output"
RESULT=$(tr -d '\r' < "$WORK/result" 2>/dev/null | sed -n 's/^RISE_VCAN_EXIT=\([0-9]\{1,3\}\)$/\1/p')
show_console() {
  log "kernel console:"
  tr -d '\r' < "$WORK/console" 2>/dev/null | tail -n 40 >&2 || true
  [ ! -s "$WORK/qemu.log" ] || { log "qemu:"; cat "$WORK/qemu.log" >&2; }
}
[ "${RISE_VCAN_VERBOSE:-0}" != 1 ] || show_console
log "pack $(( T_PACKED - T_START )) ms, vm $(( T_END - T_PACKED )) ms ($KVER, ${ACCEL[1]})"
if [ -z "$RESULT" ]; then
  [ "${RISE_VCAN_VERBOSE:-0}" = 1 ] || show_console
  case "$QEMU_RC" in
    124|137) log "TIMEOUT: the VM ran past ${TIMEOUT_S} s"; exit 124 ;;
    *)       log "no exit code from the VM (qemu exit status $QEMU_RC)"; exit 125 ;;
  esac
fi
[ "$RESULT" != 125 ] || [ "${RISE_VCAN_VERBOSE:-0}" = 1 ] || show_console
exit "$RESULT"
