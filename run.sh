#!/usr/bin/env bash
# The project's one entry point. On a fresh Debian 12 machine (as root) it
# installs what is missing, builds incrementally, then:
#   bash run.sh demo    the whole chain on built-in defaults (rise demo)
#   bash run.sh test    every test (ctest)
#   bash run.sh build   only set up and build
#   bash run.sh sanitize asan|tsan   the sanitizer builds and their tests (CI)
# Extra arguments after demo/test go to `rise demo` / ctest.
set -euo pipefail
cd "$(dirname "$(readlink -f "$0")")"
root=$PWD
build=${RISE_BUILD_DIR:-$root/build}

# Debian 12 packages: toolchain (git: `git describe` gives every program's
# --version), libraries, and the third-party peers the
# tests talk to (python3-can for socketcand, socat for pty pairs, clang's
# libFuzzer runtime for the fuzz targets, Debian's own kernel + qemu +
# can-utils for the SocketCAN tests under a real CAN stack, mbpoll and
# pymodbus as Modbus peers, hidapi + libusb for HID devices, udev's
# systemd-udevd for the USB hot-plug test inside the VM, PCL + OpenCV +
# Ceres for the semantic engine and Open3D as its benchmark peer (liboctomap
# as the OctoMap reader's peer in its test), jsoncpp for
# the training reports and journal, Chromium to render the HTML report in its
# test, and to run the instructor console's browser tests), zlib for the
# gzip'd CARMEN logs, cpp-httplib for the instructor's web server, Node.js
# + npm to build its pages from the locked npm packages in instructor/web
# (three.js, esbuild, playwright-core) at set-up, universal-ctags for the
# function-size check, iproute2 + libfaketime + curl + jq for the classroom
# test (hosts as network namespaces on a bridge, one host's clock skewed, its
# HTTP API read with curl and jq), ALSA (libasound2-dev) for rise-sound's
# playback and sox to measure its output's level in the test, libpcap to read
# pcap/pcapng captures (CAN, Modbus/TCP) with tcpdump capturing vcan in the VM
# test and tshark as the oracle of the pcap tests, libevdev for evdev://
# gamepads the kernel drives (their state, SYN_DROPPED resync, code names). Installing
# linux-image-amd64 only adds files under /boot and /lib/modules; it does not
# change how the machine boots.
packages=(
  cmake ninja-build g++ binutils pkg-config git
  libode-dev liblcm-dev liblcm-bin libeigen3-dev libyaml-cpp-dev libcli11-dev libspdlog-dev catch2 liburdfdom-dev
  python3 python3-can socat
  clang libclang-rt-14-dev
  qemu-system-x86 linux-image-amd64 busybox-static cpio can-utils
  libmodbus-dev mbpoll python3-pymodbus python3-serial-asyncio
  libhidapi-dev libusb-1.0-0-dev udev
  libevdev-dev
  libpcl-dev libopencv-dev libceres-dev libopen3d-dev liboctomap-dev
  libjsoncpp-dev chromium zlib1g-dev
  libssl-dev libcpp-httplib-dev nodejs npm
  universal-ctags
  iproute2 faketime curl jq
  libasound2-dev sox
  libassimp-dev libxml2-dev
  libpcap-dev tcpdump tshark
)

setup() {
  local missing=()
  for p in "${packages[@]}"; do
    # A nodejs that bundles npm (NodeSource's) provides it without the package.
    [ "$p" = npm ] && command -v npm >/dev/null && continue
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "run.sh: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" \
    >/tmp/rise-apt.log 2>&1 || { tail -30 /tmp/rise-apt.log; exit 1; }
}

# The instructor's pages: npm ci from package-lock.json, then the bundle
# into instructor/web/dist (served by rise-instructor serve; nothing is
# fetched when they run). Redone when the lock file or a source is newer.
web_setup() {
  local web=$root/instructor/web
  [ -f "$web/package.json" ] || return 0
  if [ ! -f "$web/node_modules/.package-lock.json" ] || [ "$web/package-lock.json" -nt "$web/node_modules/.package-lock.json" ]; then
    echo "run.sh: npm ci in instructor/web"
    (cd "$web" && npm ci --no-audit --no-fund >/tmp/rise-npm.log 2>&1) || { tail -30 /tmp/rise-npm.log; exit 1; }
  fi
  if [ ! -f "$web/dist/index.html" ] || [ -n "$(find "$web/src" "$web/build.mjs" -newer "$web/dist/index.html" 2>/dev/null | head -1)" ]; then
    (cd "$web" && node build.mjs >/dev/null) || exit 1
  fi
}

build() {
  web_setup
  local werror=OFF
  [ -n "${CI:-}" ] && werror=ON
  if [ ! -f "$build/build.ninja" ]; then
    # Optimised with debug info: the simulator's real-time factor and the
    # replay and bridge figures are those of this build (RISE_BUILD_TYPE=Debug
    # for a debugger build).
    cmake -S "$root" -B "$build" -G Ninja -DRISE_WERROR=$werror \
      -DCMAKE_BUILD_TYPE="${RISE_BUILD_TYPE:-RelWithDebInfo}" >/dev/null
  fi
  cmake --build "$build" -j2
}

# The sanitizer builds (README "Reliability"), each in its own build folder
# at -O1 with line tables, the test executables chosen there and the programs
# they start: ASan + UBSan over the parsers, the bridge, the fault paths, the
# simulator and the instructor's logic; TSan over the threaded parts (the
# bridge and its recorder, the transports' reader threads, the web server with
# the virtual panel, the trainer beside rise-sim). Every process writes its
# reports under the build's sanitizer/ folder (children too, whose own output
# goes to their logs); any report there fails the run.
sanitize() {
  local kind=$1 flags tests
  case "$kind" in
    asan) flags="address,undefined"
      tests="firmware_protocol_test firmware_protocol_hid_test msgs_test panels_test hil_io_test hil_io_slcan_test
             hil_io_capture_test hil_test hil_fault_test hil_capture_commands_test sim_test sim_control_test sim_urdf_tree_test
             instructor_test instructor_process_test training_test" ;;
    tsan) flags="thread"
      tests="hil_test hil_io_test instructor_web_test trainer_test" ;;
    *) echo "usage: bash run.sh sanitize asan|tsan" >&2; exit 2 ;;
  esac
  local dir=${build}-$kind
  web_setup
  if [ ! -f "$dir/build.ninja" ]; then
    cmake -S "$root" -B "$dir" -G Ninja -DRISE_WERROR=OFF -DRISE_SANITIZE="$flags" -DCMAKE_BUILD_TYPE=None \
      -DCMAKE_CXX_FLAGS="-O1 -g1" -DCMAKE_C_FLAGS="-O1 -g1" >/dev/null
  fi
  # shellcheck disable=SC2086
  cmake --build "$dir" -j2 --target $tests
  local reports=$dir/sanitizer
  rm -rf "$reports" && mkdir -p "$reports"
  local supp=$root/tests/sanitizer
  export ASAN_OPTIONS="log_path=$reports/asan:detect_leaks=1:abort_on_error=0:suppressions=$supp/asan.supp"
  export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
  export UBSAN_OPTIONS="log_path=$reports/ubsan:print_stacktrace=1:halt_on_error=1"
  export TSAN_OPTIONS="log_path=$reports/tsan:halt_on_error=1:second_deadlock_stack=1:suppressions=$supp/tsan.supp"
  local labels rc=0
  labels="^($(echo $tests | tr ' ' '|'))\$"
  (cd "$dir" && ctest --output-on-failure --timeout 600 -j2 -L "$labels") || rc=1
  if [ -n "$(ls -A "$reports")" ]; then
    echo "run.sh sanitize $kind: sanitizer reports:"
    for f in "$reports"/*; do echo "== $f"; head -60 "$f"; done
    rc=1
  fi
  [ $rc -eq 0 ] && echo "run.sh sanitize $kind: no sanitizer report, every test passed"
  return $rc
}

cmd=${1:-demo}
[ $# -gt 0 ] && shift
case "$cmd" in
  demo) setup; build; exec "$build/bin/rise" demo "$@" ;;
  test) setup; build; cd "$build" && exec ctest --output-on-failure --timeout 300 -j2 "$@" ;;
  build) setup; build ;;
  sanitize) setup; sanitize "${1:-}" ;;
  *) echo "usage: bash run.sh demo|test|build|sanitize asan|tsan [args]" >&2; exit 2 ;;
esac
