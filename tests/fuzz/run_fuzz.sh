#!/usr/bin/env bash
# Builds one libFuzzer target with clang and runs it for a bounded number of
# inputs from a seed corpus this script writes itself (nothing binary is kept
# in the repository).
#   run_fuzz.sh CLANGXX ROOT WORKDIR TARGET RUNS
# RUNS -1: no bound but the time, RISE_FUZZ_SECONDS (default 50);
# RISE_FUZZ_BUILD_ONLY=1: compile and stop (bench/fuzz_all builds them all first).
# TARGET is console_can, console_modbus, dbc, canopen_eds, j1939, hid_descriptor, ply, scan3d, pcd, maps, carmen, logs,
# line_protocols, command_auth, inputs, configs, training_graph, training_builder, world_builder, robot_builder, task_builder, console_builder, urdf, mesh, web_requests or lcm_messages; sources are tests/fuzz/TARGET_fuzz.cpp plus the
# library sources it needs. Crash inputs land in WORKDIR/TARGET-artifacts/.
set -euo pipefail
clangxx=$1 root=$2 work=$3 target=$4 runs=$5

case "$target" in
  console_can) sources=("$root/firmware_protocol/console_can.cpp") ;;
  console_modbus) sources=("$root"/firmware_protocol/console_{can,modbus}.cpp) ;;
  dbc) sources=("$root/firmware_protocol/dbc.cpp") ;;
  canopen_eds) sources=("$root"/firmware_protocol/{canopen,canopen_eds,dbc}.cpp) ;;
  j1939) sources=("$root/firmware_protocol/j1939.cpp") ;;
  hid_descriptor) sources=("$root"/firmware_protocol/hid_{descriptor,report,text}.cpp) ;;
  # The semantic readers: PLY/XYZ and 3DTK/sim poses without PCL; the PCD
  # target adds our cloud_io.cpp and links the system's PCL (not sanitized).
  ply | scan3d) sources=("$root"/semantic/{cloud,cloud_formats,text_reading}.cpp) ;;
  maps) sources=("$root"/semantic/{cloud,cloud_formats,text_reading,octomap_format,vtk_format}.cpp) ;;
  pcd) sources=("$root"/semantic/{cloud,cloud_formats,text_reading,cloud_io,octomap_format,vtk_format}.cpp) ;;
  # The CARMEN log reader and grid_from_scans (occupancy_grid.cpp links
  # yaml-cpp, OpenCV and zlib for the other readers there; not sanitized).
  carmen) sources=("$root"/semantic/{cloud,cloud_formats,text_reading,occupancy_grid}.cpp) ;;
  # The recordings (CAN logs, Modbus traces, hid-recorder files), the
  # socketcand and slcan line protocols, the signed-command verifier (its
  # two message types generated here by lcm-gen) and the YAML files users
  # write (panels, robots with their URDF, worlds, tasks, scenarios).
  logs) sources=("$root"/hil/io/{can_log,can_log_binary,candump_log,can_frame,modbus_trace,modbus_capture,hid_recording,record_file}.cpp) ;;
  line_protocols) sources=("$root"/hil/io/{slcan_wire,socketcand_wire,can_frame}.cpp) ;;
  command_auth) sources=("$root/msgs/command_auth.cpp") ;;
  # Console scripts against the shipped console, pose graphs, key files, URLs.
  inputs) sources=("$root"/panels/{panel_definition,canopen_definition,yaml_reader,modbus_point,timeline}.cpp
                   "$root"/firmware_protocol/{console_can,dbc,sdl_mapping,canopen,canopen_eds}.cpp
                   "$root"/semantic/{pose_graph_io,cloud_formats,text_reading,cloud}.cpp "$root/msgs/command_auth.cpp"
                   "$root"/hil/io/{can_url,modbus_url,host_port,hid_device,usb_hotplug,evdev_device,posix_io}.cpp) ;;
  configs)
    sources=("$root"/panels/{panel_definition,canopen_definition,yaml_reader,yaml_writer,modbus_point}.cpp
             "$root"/firmware_protocol/{console_can,dbc,sdl_mapping,canopen,canopen_eds}.cpp
             "$root"/sim/{robot_description,urdf_robot,urdf_tree,mesh_file,collada_geometry,world_description}.cpp "$root"/sim/training/{task_description,yaml_comments}.cpp
             "$root/instructor/scenario.cpp")
    ;;
  # The training graph without its tasks (TaskResult is apart from the
  # executor, so neither the executor nor the simulator is linked).
  training_graph)
    sources=("$root"/sim/training/{training_graph,training_writer,task_result,task_description,yaml_comments}.cpp "$root"/sim/world_description.cpp
             "$root"/panels/{yaml_reader,yaml_writer}.cpp)
    ;;
  # The Training Builder's request body: JSON → graph → YAML → the trainer's
  # loader with the shipped task files (design_files.cpp: the name check; its
  # atomic save is report.cpp's).
  training_builder)
    sources=("$root"/instructor/{training_builder,design_files,builder_errors}.cpp
             "$root"/sim/training/{training_graph,training_writer,task_result,task_description,report,yaml_comments}.cpp
             "$root"/sim/world_description.cpp "$root"/panels/{yaml_reader,yaml_writer}.cpp)
    ;;
  # The Task Builder's request body: JSON → task → YAML → the trainer's loader
  # and the task's world (training_builder.cpp: the errors' JSON).
  task_builder)
    sources=("$root"/instructor/{task_builder,training_builder,design_files,builder_errors}.cpp
             "$root"/sim/training/{task_writer,training_graph,training_writer,task_result,task_description,report,yaml_comments}.cpp
             "$root"/sim/world_description.cpp "$root"/panels/{yaml_reader,yaml_writer}.cpp)
    ;;
  # The Environment Builder's body (JSON → world → YAML → rise-sim's loader) and world files written back.
  world_builder)
    sources=("$root"/instructor/{world_builder,builder_errors}.cpp "$root"/sim/{world_writer,world_description}.cpp "$root"/panels/{yaml_reader,yaml_writer}.cpp) ;;
  # The Robot Builder's request body: its edits written in place into a
  # robot's text (sim/yaml_edit.cpp) and loaded as rise-sim loads it;
  # web_json.cpp draws the view (its message types by lcm-gen here).
  robot_builder)
    sources=("$root"/instructor/{robot_builder,builder_errors,web_json,trainee_directory}.cpp "$root"/msgs/{channels,publisher_session,failsafe}.cpp
             "$root"/sim/{yaml_edit,robot_description,urdf_robot,urdf_tree,mesh_file,collada_geometry,world_description}.cpp
             "$root"/panels/{yaml_reader,yaml_writer}.cpp)
    ;;
  # The Console Builder's request body: JSON → controls → the panel's text →
  # rise-hild's loader (no server, no sources: console_builder_model.cpp).
  console_builder)
    sources=("$root"/instructor/{console_builder_model,builder_errors}.cpp
             "$root"/panels/{panel_writer,panel_definition,canopen_definition,yaml_reader,modbus_point}.cpp
             "$root"/firmware_protocol/{console_can,dbc,sdl_mapping,canopen,canopen_eds}.cpp)
    ;;
  urdf) sources=("$root"/sim/{urdf_robot,urdf_tree,mesh_file,collada_geometry}.cpp) ;;
  mesh) sources=("$root"/sim/{mesh_file,collada_geometry}.cpp) ;;
  # The messages of the multicast group as the instructor takes them (every type by lcm-gen here).
  lcm_messages)
    sources=("$root"/msgs/{channels,publisher_session,failsafe}.cpp "$root"/instructor/{web_json,trainee_directory}.cpp
             "$root"/sim/world_description.cpp "$root"/panels/yaml_reader.cpp)  # web_json's world_json
    ;;
  # The web console's request readers (no server; FaultCommand by lcm-gen here).
  web_requests) sources=("$root"/instructor/{web_requests,fault_presets}.cpp) ;;
  *) echo "run_fuzz.sh: unknown target $target" >&2; exit 2 ;;
esac
sources+=("$root/tests/fuzz/${target}_fuzz.cpp")
binary="$work/${target}_fuzz"
mkdir -p "$work"

# Rebuild only when a source or header is newer than the binary.
rebuild=0
[ -x "$binary" ] || rebuild=1
for f in "${sources[@]}" "$root/msgs/lcm_gen.sh" "$root"/tests/fuzz/*.hpp "$root"/{firmware_protocol,semantic,msgs,hil/io,panels,sim,sim/training,instructor}/*.hpp; do
  [ "$f" -nt "$binary" ] && rebuild=1
done
if [ $rebuild -eq 1 ]; then
  echo "run_fuzz.sh: compiling $binary"
  flags=() libs=()
  case "$target" in
    ply | scan3d | maps) flags=(-isystem /usr/include/eigen3) ;;
    carmen)
      flags=(-isystem /usr/include/eigen3 -isystem /usr/include/opencv4)
      libs=(-lyaml-cpp -lopencv_imgcodecs -lopencv_core -lz)
      ;;
    pcd)
      flags=(-isystem /usr/include/eigen3 -isystem /usr/include/pcl-1.13)
      libs=(-lpcl_io -lpcl_common -lboost_filesystem)
      ;;
    command_auth)
      bash "$root/msgs/lcm_gen.sh" lcm-gen "$work/lcmgen" "$root"/msgs/lcmtypes/{FaultCommand,TrainingControl}.lcm
      flags=(-I"$work/lcmgen")
      libs=(-lcrypto)
      ;;
    logs) libs=(-lpcap -lz) ;;
    inputs)
      bash "$root/msgs/lcm_gen.sh" lcm-gen "$work/lcmgen" "$root"/msgs/lcmtypes/{FaultCommand,TrainingControl}.lcm
      flags=(-I"$work/lcmgen" -isystem /usr/include/eigen3 -isystem /usr/include/libevdev-1.0 -isystem /usr/include/libusb-1.0 -DRISE_FUZZ_ROOT="\"$root\"")
      libs=(-lyaml-cpp -lcrypto -lhidapi-hidraw -lusb-1.0 -levdev)
      ;;
    web_requests)
      bash "$root/msgs/lcm_gen.sh" lcm-gen "$work/lcmgen" "$root/msgs/lcmtypes/FaultCommand.lcm"
      flags=(-I"$work/lcmgen" -isystem /usr/include/jsoncpp)
      libs=(-ljsoncpp)
      ;;
    lcm_messages)
      bash "$root/msgs/lcm_gen.sh" lcm-gen "$work/lcmgen-all" "$root"/msgs/lcmtypes/*.lcm
      flags=(-I"$work/lcmgen-all" -isystem /usr/include/jsoncpp -isystem /usr/include/eigen3)
      libs=(-ljsoncpp -llcm -lyaml-cpp)
      ;;
    world_builder)
      flags=(-isystem /usr/include/eigen3 -isystem /usr/include/jsoncpp -DRISE_SOURCE_DIR="\"$root\"")
      libs=(-lyaml-cpp -ljsoncpp)
      ;;
    urdf) flags=(-isystem /usr/include/eigen3 -isystem /usr/include/libxml2) libs=(-lurdfdom_model -lconsole_bridge -lassimp -lxml2) ;;
    mesh) flags=(-isystem /usr/include/libxml2) libs=(-lassimp -lxml2) ;;
    training_graph) flags=(-isystem /usr/include/eigen3) libs=(-lyaml-cpp) ;;
    training_builder | task_builder)
      flags=(-isystem /usr/include/eigen3 -isystem /usr/include/jsoncpp -DRISE_SOURCE_DIR="\"$root\"")
      libs=(-lyaml-cpp -ljsoncpp)
      ;;
    robot_builder)
      bash "$root/msgs/lcm_gen.sh" lcm-gen "$work/lcmgen-all" "$root"/msgs/lcmtypes/*.lcm
      flags=(-I"$work/lcmgen-all" -isystem /usr/include/eigen3 -isystem /usr/include/jsoncpp -isystem /usr/include/libxml2 -DRISE_SOURCE_DIR="\"$root\"")
      libs=(-ljsoncpp -llcm -lyaml-cpp -lurdfdom_model -lconsole_bridge -lassimp -lxml2)
      ;;
    console_builder)
      flags=(-isystem /usr/include/eigen3 -isystem /usr/include/jsoncpp -DRISE_SOURCE_DIR="\"$root\"")
      libs=(-lyaml-cpp -ljsoncpp)
      ;;
    configs)
      flags=(-isystem /usr/include/eigen3 -isystem /usr/include/libxml2)
      libs=(-lyaml-cpp -lurdfdom_model -lconsole_bridge -lassimp -lxml2)
      ;;
  esac
  "$clangxx" -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
    -I"$root" "${flags[@]}" "${sources[@]}" -o "$binary.tmp" "${libs[@]}"
  mv "$binary.tmp" "$binary"
fi

[ "${RISE_FUZZ_BUILD_ONLY:-0}" = 1 ] && exit 0

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
  canopen_eds)
    # A byte first: the node id - 1. The shipped console's EDS; a DCF with
    # ParameterValue, 0-octal, a 29-bit COB-ID, dummies and a REAL32 object.
    { printf '\x04'; cat "$root/panels/definitions/rise_console_canopen.eds"; } >"$corpus/console.eds"
    printf '\x10[1017]\nParameterName=HB\nDataType=0x0006\nDefaultValue=50\nParameterValue=020\n[1800sub1]\nParameterName=C\nDataType=0x0007\nDefaultValue=0x20000180+$NODEID\n[1800sub2]\nParameterName=T\nDataType=0x0005\nDefaultValue=0\n[1A00sub0]\nParameterName=N\nDataType=0x0005\nDefaultValue=3\n[1A00sub1]\nParameterName=M1\nDataType=0x0007\nDefaultValue=0x20000120\n[1A00sub2]\nParameterName=M2\nDataType=0x0007\nDefaultValue=0x00050008\n[1A00sub3]\nParameterName=M3\nDataType=0x0007\nDefaultValue=0x20000201\n[2000]\nParameterName=R\nObjectType=0x9\nSubNumber=3\n[2000sub1]\nParameterName=Speed\nDataType=0x0008\nPDOMapping=1\nLowLimit=-10\nHighLimit=10\n[2000sub2]\nParameterName=On\nDataType=0x0001\nPDOMapping=1\n' >"$corpus/dcf.dcf"
    extra=(-dict="$root/tests/fuzz/canopen_eds.dict")
    ;;
  j1939)
    # Our address 0x80. A 20-byte BAM of PGN 0xFF20 from 0x21 (CM + 3 DT);
    # an RTS/CTS of 10 bytes to 0x80 (RTS, 2 DT); a contending claim of 0x80
    # by a lower NAME; an RTS left to time out (time step 15 x 100 ms).
    printf '\x80\x21\xff\xec\x1c\x08\x20\x14\x00\x03\xff\x20\xff\x00\x21\xff\xeb\x1c\x08\x01\x01\x02\x03\x04\x05\x06\x07\x21\xff\xeb\x1c\x08\x02\x08\x09\x0a\x0b\x0c\x0d\x0e\x21\xff\xeb\x1c\x08\x03\x0f\x10\x11\x12\x13\x14\xff' >"$corpus/bam"
    printf '\x80\x21\x80\xec\x1c\x08\x10\x0a\x00\x02\xff\x00\xff\x00\x21\x80\xeb\x1c\x08\x01\x01\x02\x03\x04\x05\x06\x07\x21\x80\xeb\x1c\x08\x02\x08\x09\x0a\xff\xff\xff\xff' >"$corpus/rts_cts"
    printf '\x80\x80\xff\xee\x18\x08\x01\x00\x00\x00\x00\x00\x00\x00\x21\xff\xea\x18\x03\x00\xee\x00' >"$corpus/claim"
    printf '\x80\x21\x80\xec\x1c\x08\x10\x0a\x00\x02\xff\x00\xff\x00\x21\x80\xeb\x1c\xf8\x01\x01\x02\x03\x04\x05\x06\x07' >"$corpus/timeout"
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
  ply)
    printf 'ply\nformat ascii 1.0\ncomment seed\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1 255\n1 0 0 0 0 1 0\n0 1 0 0 0 1 7\n3 0 1 2\n' >"$corpus/ascii.ply"
    printf 'ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n\x00\x00\x80\x3f\x00\x00\x00\x40\x00\x00\x40\x40\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00' >"$corpus/le.ply"
    printf 'ply\nformat binary_big_endian 1.0\nelement face 1\nproperty list uchar int vertex_indices\nelement vertex 1\nproperty double x\nproperty double y\nproperty double z\nend_header\n\x01\x00\x00\x00\x00\x3f\xf0\x00\x00\x00\x00\x00\x00\x40\x00\x00\x00\x00\x00\x00\x00\x40\x08\x00\x00\x00\x00\x00\x00' >"$corpus/be.ply"
    printf '1 2 3\n4 5 6\n# comment\n-1e3 0.5 nan\n' >"$corpus/points.xyz"
    ;;
  scan3d)
    printf '360 x 225\n10.1 0 0\n-3.5 2e1 400\n' >"$corpus/header.3d"
    printf -- '-3.10605 -7.50803 156.917\n1.35694 -0.852409 -0.56224\n' >"$corpus/scan.pose"
    printf '1 0 0 0 0 1 0 0 0 0 1 0 -3.6 -9.1 156.8 1 2\n' >"$corpus/scan.frames"
    printf '# rise-sim\ntime_s 1\nposition_m 0.25 0 0.3\norientation_wxyz 0.7071 0.7071 0 0\nmatrix_row_major 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n' >"$corpus/sim.pose"
    if [ -n "${RISE_TEST_DATA:-}" ] && [ -d "$RISE_TEST_DATA/pointclouds/3DTK-dat" ]; then
      for f in "$RISE_TEST_DATA"/pointclouds/3DTK-dat/scan00{0,1}.{pose,frames}; do cp "$f" "$corpus/"; done
      head -c 4000 "$RISE_TEST_DATA/pointclouds/3DTK-dat/scan000.3d" >"$corpus/scan000-head.3d"
    fi
    ;;
  maps)
    # A .bt root whose inner child has a free and an occupied child, a
    # ColorOcTree .ot of two nodes, VTK ASCII (version 5.1) and BINARY (4.2).
    printf '# Octomap OcTree binary file\nid OcTree\nsize 4\nres 0.1\ndata\n\x03\x00\x09\x00' >"$corpus/tree.bt"
    printf '# Octomap OcTree file\nid ColorOcTree\nsize 2\nres 0.05\ndata\n\x00\x00\x60\x40\x01\x02\x03\x80\x00\x00\x60\x40\x01\x02\x03\x00' >"$corpus/tree.ot"
    printf '# vtk DataFile Version 5.1\nvtk output\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n0 0 0 1 2 3\nVERTICES 3 2\nOFFSETS vtktypeint64\n0 1 2\nCONNECTIVITY vtktypeint64\n0 1\nPOINT_DATA 2\nSCALARS s int 1\nLOOKUP_TABLE default\n1 2\nNORMALS n float\n0 0 1 0 1 0\nFIELD FieldData 1\nf 2 2 double\n1 2 3 4\nMETADATA\nINFORMATION 0\n\n' >"$corpus/ascii.vtk"
    printf '# vtk DataFile Version 4.2\nt\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 float\n\x3f\x80\x00\x00\x40\x00\x00\x00\x40\x40\x00\x00\nCELLS 1 2\n\x00\x00\x00\x01\x00\x00\x00\x00\nCELL_TYPES 1\n\x00\x00\x00\x01\n' >"$corpus/binary.vtk"
    if [ -n "${RISE_TEST_DATA:-}" ] && [ -f "$RISE_TEST_DATA/pointclouds/ANYbotics_grid_map/freiburg1_360.bt" ]; then
      head -c 3000 "$RISE_TEST_DATA/pointclouds/ANYbotics_grid_map/freiburg1_360.bt" >"$corpus/freiburg-head.bt"
    fi
    ;;
  pcd)
    printf 'VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary\n\x00\x00\x80\x3f\x00\x00\x00\x40\x00\x00\x40\x40\x00\x00\xc0\x7f\x00\x00\x00\x00\x00\x00\x00\x00' >"$corpus/binary.pcd"
    printf 'VERSION .7\nFIELDS x y z normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4\nTYPE F F F F F F\nCOUNT 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3 0 0 1\nnan nan nan 0 0 1\n' >"$corpus/ascii.pcd"
    if [ -n "${RISE_TEST_DATA:-}" ] && [ -d "$RISE_TEST_DATA/pointclouds/pcl" ]; then
      find "$RISE_TEST_DATA/pointclouds/pcl" -name '*.pcd' -size -20k -exec cp {} "$corpus/" \;
    fi
    ;;
  carmen)
    printf 'PARAM robot_front_laser_max 50 nohost 0\nODOM 0 0 0 0 0 0 1 h 1\nFLASER 3 1.0 81.9 2.5 0.5 -0.2 0.1 0.5 -0.2 0.1 2.0 h 2.0\n' >"$corpus/flaser.log"
    printf 'ROBOTLASER1 0 -1.5 3.0 0.75 30 0.01 0 5 1 2 3 4 5 0 1.0 2.0 0.5 1.0 2.0 0.5 0 0 0 0 0 7.5 h 7.5\n' >"$corpus/robotlaser.log"
    if [ -n "${RISE_TEST_DATA:-}" ] && [ -f "$RISE_TEST_DATA/pointclouds/acschaefer_ple/intel-corrected.log.gz" ]; then
      zcat "$RISE_TEST_DATA/pointclouds/acschaefer_ple/intel-corrected.log.gz" | head -60 >"$corpus/intel.log" || true  # zcat's SIGPIPE
    fi
    ;;
  logs)
    # A byte first: the reader (0 candump .log, 1 ASC, 2 TRC, 3 Modbus trace, 4 hid-recorder,
    # 5 BLF, 6 pcap/pcapng: the format from the magic bytes, 7 a Modbus/TCP capture).
    if [ -n "${RISE_TEST_DATA:-}" ] && [ -d "$RISE_TEST_DATA/can" ]; then
      { printf '\x05'; cat "$RISE_TEST_DATA/can/python-can/test_CanMessage.blf"; } >"$corpus/test_CanMessage.blf"
      { printf '\x06'; head -c 3000 "$RISE_TEST_DATA/modbus/zeek/modbusSmall.pcap"; } >"$corpus/modbusSmall.pcap"
      for f in "$RISE_TEST_DATA"/modbus/zeek/{modbusSmall,modbus-eit}.pcap; do
        { printf '\x07'; head -c 6000 "$f"; } >"$corpus/capture-$(basename "$f")"
      done
      for f in "$RISE_TEST_DATA"/can/python-can/*.asc; do { printf '\x01'; head -c 6000 "$f"; } >"$corpus/$(basename "$f")"; done
      for f in "$RISE_TEST_DATA"/can/python-can/*.trc; do { printf '\x02'; cat "$f"; } >"$corpus/$(basename "$f")"; done
      { printf '\x00'; head -40 "$RISE_TEST_DATA/can/ICSim/sample-can.log"; } >"$corpus/icsim.log"
      for f in "$RISE_TEST_DATA"/hid/hid-tools_{AsusGamepad,SaitekGamepad}.hid; do { printf '\x04'; head -c 6000 "$f"; } >"$corpus/$(basename "$f")"; done
    fi
    { printf '\x00'; head -40 "$root/tests/data/replay/can/console.log"; } >"$corpus/console.log"
    { printf '\x03'; head -40 "$root/tests/data/replay/modbus/console.modbus.log"; } >"$corpus/console.modbus.log"
    { printf '\x04'; head -c 6000 "$root/tests/data/replay/hid/pad.hid"; } >"$corpus/pad.hid"
    ;;
  line_protocols)
    # A byte first: the TCP chunk size - 1; the socketcand messages and slcan lines of their headers' examples.
    printf '\x10< hi >< ok >< frame 123 1700000000.123456 0A1B2C >< frame 1ABCDEF0 1700000000.123456  >< fdframe 123 01 1700000000.123456 000102030405060708090A0B >< rtr 123 1700000000.123456 4 >< error 004 1700000000.123456 >< send 123 3 0A 1B 2C >< fdsend 123 1 12 00 01 02 03 04 05 06 07 08 09 0A 0B >< sendrtr 123 4 >' >"$corpus/socketcand"
    printf '\x03t1233112233\rT1ABCDEF02DEAD\rr3212\rt12331122331F40\rz\rR1ABCDEF08\r' >"$corpus/slcan"
    ;;
  configs)
    # A byte first: the parser (0 panel, 1 robot, 2 world, 3 task, 4 scenario); the project's own files
    # (the tasks, not fig10_training.yaml: a training graph).
    for spec in "00:$root/panels/definitions/*.yaml" "01:$root/sim/robots/*.yaml" "02:$root/sim/worlds/*.yaml" \
                "03:$root/sim/training/examples/[anm]*.yaml" "04:$root/instructor/scenarios/*.yaml"; do
      for f in ${spec#*:}; do
        { printf "\x${spec%%:*}"; cat "$f"; } >"$corpus/${spec%%:*}-$(basename "$f")"
      done
    done
    ;;
  training_graph)
    # A byte first: the walk's results; the Fig. 10 example, a loop with an
    # exit through a condition on an event, and one with a closed loop.
    { printf '\x00'; cat "$root/sim/training/examples/fig10_training.yaml"; } >"$corpus/fig10.yaml"
    { printf '\x35'; cat "$root/sim/training/examples/fig10_training.yaml"; } >"$corpus/fig10-b.yaml"
    printf '\x11training: t\nnodes:\n  - {name: a, task: a.yaml, max_attempts: 3}\n  - {name: b, task: /b.yaml}\ntransitions:\n  - {from: START, to: a}\n  - {from: a, if: "events.neutralized GE 1", to: b}\n  - {from: a, if: "time_s LE 1e2", to: a}\n  - {from: b, if: "success NE false", to: END}\n  - {from: b, to: a}\n' >"$corpus/loop.yaml"
    # Comments and strings the writer must quote (the Training Builder saves through it).
    printf '\x07# head\n#  two\n\ntraining: "a: \\"b\\" #c"\ntitle: \x27it\x27\x27s\x27\nnodes:\n  - {name: "yes", task: "../x y.yaml"}  # n # m\ntransitions:\n  - {from: START, to: "yes"}   #s\n  - {from: "yes", if: "result GE 1e1", to: END} # \x27q\x27\n' >"$corpus/quoted.yaml"
    printf '\x02training: t\nnodes:\n  - name: a\n    task: a.yaml\n  - name: b\n    task: b.yaml\ntransitions:\n  - {from: START, to: a}\n  - {from: a, to: b}\n  - {from: b, to: a}\n  - {from: c, to: END}\n' >"$corpus/closed.yaml"
    ;;
  urdf)
    # A byte first: the joints asked for (bit 0 skid4's wheels, bit 1 tracked_eod's arm; bit 2: the
    # general tree, sim/urdf_tree.hpp, meshes by name only); the project's robots and the tree test rig.
    # No leak detection: liburdfdom 3.0 leaks part of its tree on some refused
    # files (parseURDF's error path, not our code; a robot file is loaded once).
    export ASAN_OPTIONS=detect_leaks=0
    extra=(-dict="$root/tests/fuzz/urdf.dict")
    # The smallest robot our checks take, where a mutation reaches every number.
    printf '\x00<robot name="r"><link name="base"><inertial><mass value="6"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial><collision><geometry><box size="1 1 1"/></geometry></collision></link></robot>\n' >"$corpus/box.urdf"
    for b in 0 1 2 3 4; do
      for f in "$root"/sim/robots/*.urdf "$root/tests/sim/data/pan_tilt.urdf"; do
        { printf "\\x0$b"; cat "$f"; } >"$corpus/$b-$(basename "$f")"
      done
    done
    ;;
  mesh)
    # A byte first: bit 0 COLLADA, else STL. The shipped robot's binary STLs, an ASCII STL and the COLLADA cube.
    # No leak detection: libassimp 5.2 leaks its half-built mesh on a malformed
    # ASCII STL (its importer's error path, not our code; a mesh is read once).
    export ASAN_OPTIONS=detect_leaks=0
    for f in "$root"/sim/robots/meshes/*.stl; do { printf '\x00'; cat "$f"; } >"$corpus/$(basename "$f")"; done
    printf '\x00solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n' >"$corpus/ascii.stl"
    { printf '\x01'; cat "$root/tests/sim/data/cube.dae"; } >"$corpus/cube.dae"
    ;;
  training_builder)
    # The page's graph of the shipped training (as /api/builder/training/NAME
    # gives it), one with an edge added and one with errors of each kind.
    g='{"training":"fig10_metro","title":"t","comment":"c\\nd","nodes":[{"name":"mission1","task":"approach_object.yaml","max_attempts":2,"comment":"x"},{"name":"mission2","task":"neutralize_object.yaml","max_attempts":2,"comment":""}],"transitions":[{"from":"START","to":"mission1","if":"","comment":""},{"from":"mission1","to":"mission2","if":"success EQ 1","comment":"C2"},{"from":"mission1","to":"mission1","if":"","comment":"repeat"},{"from":"mission1","to":"END","if":"","comment":""},{"from":"mission2","to":"END","if":"events.neutralized GE 1","comment":""},{"from":"mission2","to":"END","if":"","comment":""}]}'
    printf '%s' "$g" >"$corpus/graph.json"
    printf '%s' "${g/\"if\":\"success EQ 1\"/\"if\":\"score LT five\"}" >"$corpus/bad-condition.json"
    printf '%s' '{"training":"t","nodes":[{"name":"a","task":"../x.yaml"},{"name":"b","task":"metro_transport.yaml","max_attempts":0}],"transitions":[{"from":"START","to":"c"},{"from":"a","to":"a","if":"events.nope GE 1"}]}' >"$corpus/errors.json"
    ;;
  world_builder)
    # Byte 0: a page's body (a world of each kind of entry; one with errors); else the shipped world files.
    printf '\x00%s' '{"world":"w","ground_friction":1,"robot_start":{"xy_m":[0,0],"yaw_deg":0},"robot_starts":[{"xy_m":[1,1],"yaw_deg":90}],"ceiling":{"height_m":2.6,"thickness_m":0.1,"follows_walls":true},"boxes":[{"name":"b","center_m":[3,3,0.3],"size_m":[0.6,0.6,0.6],"yaw_deg":23}],"props":[{"name":"p","kind":"shelf","center_m":[5,5,1],"size_m":[0.4,2,2],"yaw_deg":45}],"walls":[{"name":"w1","from":[-4,-3],"to":[9,-3],"height":2.5,"thickness":0.15,"openings":[{"at_m":3,"width_m":0.9,"height_m":2}]}],"doors":[{"name":"d","hinge":[-1,-3],"width":0.9,"yaw_deg":0,"open_deg_max":100,"break_torque_nm":900}],"stairs":[{"name":"s","start":[0.5,4.25],"yaw_deg":0,"steps":6}],"objects":[{"name":"o","size_m":[0.3,0.3,0.3],"mass_kg":4,"center_m":[6,1.5,0.15]}],"regions":[{"name":"r","min":[7,-2.5,0],"max":[8.5,-1,1.5]}]}' >"$corpus/world.json"
    printf '\x00%s' '{"world":"w","walls":[{"name":"w","from":[0,0],"to":[0,0],"openings":[{"at_m":-1}]}],"doors":[{"name":"w","hinge":[0,0],"width":-1}],"stairs":[{"name":"s","start":[0,0],"steps":0}]}' >"$corpus/errors.json"
    for f in "$root"/sim/worlds/*.yaml; do { printf '\x01'; cat "$f"; } >"$corpus/$(basename "$f")"; done
    ;;
  robot_builder)
    # The page's bodies on skid4.yaml (a limit, an invert added, a picked
    # button, a bad value, a bad path), and edits of a text of every YAML form.
    printf '{"version":"x","edits":[{"path":"control.linear.max_mps","value":"0.3"},{"path":"control.linear.invert","value":"true"}]}' >"$corpus/limit.json"
    printf '{"edits":[{"path":"sounds.horn.button","value":"gripper_open"},{"path":"wheels.max_torque_nm","value":"-1"}]}' >"$corpus/bad.json"
    printf '{"edits":[{"path":"control.speed_scale.values[2]","value":"two words"},{"path":"control..x","value":"1"}]}' >"$corpus/paths.json"
    printf 'a: {b: 1, c: "q\\"", d: [1, 2]}  # c\nl:\n  - {x: 1}\n  - y\nm:\n  n: 2\n\0[{"path":"a.e","value":"1"},{"path":"l[0].z","value":"#"},{"path":"m.o.p","value":""}]' >"$corpus/forms"
    ;;
  task_builder)
    # The page's task of the shipped approach_object.yaml (as /api/builder/task/NAME
    # gives it), one with an event of every kind, and one with errors of each kind.
    t='{"task":"approach_object","title":"Drive up","comment":"Mission 1\\nof two","robot":"../../robots/tracked_eod.yaml","world":"../../worlds/building.yaml","panel":"../../../panels/definitions/rise_console.yaml","console_script":"approach_object_console.txt","scenario":"","start":{"x":4,"y":0,"yaw_deg":36.87},"time_limit_s":30,"regions":[{"name":"near_object","min":[4.8,0.4,0],"max":[6.6,2.2,1],"comment":"r"}],"events":[{"name":"near_object","kind":"reach_region","region":"near_object","points":10,"max_count":1,"comment":"c"},{"name":"object_touched","kind":"touch_object","object":"hazardous_object","points":10},{"name":"slow","kind":"time_exceeded","after_s":20,"points":-5},{"name":"bump","kind":"collision","except":["hazardous_object"],"points":-2}],"end_on":["object_touched"],"success":["object_touched"],"key_comments":{"world":"w"}}'
    printf '%s' "$t" >"$corpus/task.json"
    printf '%s' "${t/\"end_on\":\[\"object_touched\"\]/\"end_on\":[\"object_touched\",\"nope\"]}" >"$corpus/bad-end.json"
    printf '%s' '{"task":"k","robot":"r.yaml","world":"../../worlds/building.yaml","events":[{"name":"a","kind":"object_in_region","object":"hazardous_object","region":"neutralization_area","hold_s":1},{"name":"b","kind":"neutralize_object","object":"hazardous_object","within_m":0.4,"hold_s":2},{"name":"c","kind":"robot_damaged","max_count":0},{"name":"d","kind":"robot_disabled"},{"name":"e","kind":"collision","per":"second"}]}' >"$corpus/kinds.json"
    printf '%s' '{"task":"","robot":"","world":"x.yaml","time_limit_s":-1,"regions":[{"name":"z","min":[1,1,1],"max":[0,0,0]}],"events":[{"name":"a","kind":"reach_region","region":"nowhere","object":"o","after_s":-1},{"name":"a","kind":"time_exceeded"}],"success":["q"]}' >"$corpus/errors.json"
    ;;
  console_builder)
    # The page's controls: rise_console.yaml's as /api/builder/console/NAME
    # gives them, one with a learned button added, one with errors.
    c='{"controls":[{"comment":"Drive stick","fields":[["name","drive_x"],["kind","axis"],["signal","axis.0"],["deadband","0.05"],["motion","true"],["safe","0.0"]]},{"comment":"","fields":[["name","deadman"],["kind","button"],["signal","button.0"],["role","deadman"],["safe","false"]]},{"comment":"","fields":[["name","mode"],["kind","switch"],["signal","switch.0"],["positions",["drive","arm"]],["safe","drive"]]}]}'
    printf '%s' "$c" >"$corpus/controls.json"
    printf '%s' '{"controls":[{"comment":"learned: button.7\nsecond","fields":[["name","horn: x"],["kind","button"],["signal","button.7"],["safe",false]]},{"comment":"","fields":[["name","lever"],["kind","axis"],["signal","axis.5"],["invert","true"],["deadband",0.05],["safe","0.0"]]}]}' >"$corpus/learned.json"
    printf '%s' '{"controls":[{"fields":[["name","a"],["kind","axis"],["signal","axis.9"],["safe",1]]},{"fields":[["name","a"],["kind","knob"]]},{"fields":[["range",[1,[2]]]]}]}' >"$corpus/errors.json"
    ;;
  web_requests)
    # The bodies the pages and tests/instructor/web_server_test.cpp post, and a cookie header.
    printf '{"axes":{"drive_y":0.8},"buttons":{"deadman":true,"estop":false},"switches":{"mode":"drive","speed":"fast"}}' >"$corpus/virtual.json"
    printf '{"trainee":"t1","fault":"stick-stuck"}' >"$corpus/preset.json"
    printf '{"trainee":"t1","fault":"*"}' >"$corpus/clear.json"
    printf '{"trainee":"t-2.a","fault":"f","kind":"noise","target":"drive_x","value":0.5,"rate":1e-3,"duration_s":2,"seed":-7}' >"$corpus/fields.json"
    printf '{"trainee":"t1","file":"stuck.yaml","seed":11}' >"$corpus/scenario.json"
    printf 'a=b; rise_token=abc123;theme=dark' >"$corpus/cookie"
    ;;
  inputs)
    # A byte first: 0 console script, 1 pose graph, 2 key file, 3 URLs. The
    # demo's script; the real g2o / EDGE3 graphs' first lines; a key; the
    # README's URL examples.
    { printf '\x00'; cat "$root/panels/scripts/demo_drive.txt"; } >"$corpus/demo_drive.txt"
    if [ -n "${RISE_TEST_DATA:-}" ] && [ -d "$RISE_TEST_DATA/posegraphs" ]; then
      for f in "$RISE_TEST_DATA"/posegraphs/*/*; do { printf '\x01'; head -60 "$f"; } >"$corpus/1-$(basename "$f")"; done
    fi
    printf '\x01VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0.1\nEDGE_SE2 0 1 1 0 0.1 500 0 0 500 0 5000\nFIX 0\n' >"$corpus/se2.g2o"
    printf '\x01VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nEDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 100 0 0 0 0 0 100 0 0 0 0 100 0 0 0 400 0 0 400 0 400\n' >"$corpus/se3.g2o"
    printf '\x02# rise instructor key\n00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff\n' >"$corpus/key"
    n=0
    for u in socketcan://can0 'slcan:///dev/ttyACM0?bitrate=500000&listen_only=1' socketcand://10.0.0.2:29536/can0 \
             'replay://a.log?speed=2&loop=1' mem://bus 'modbus+tcp://127.0.0.1:1502?unit=3&timeout_ms=200' \
             'modbus+rtu:///dev/ttyUSB0?baud=19200&parity=E&unit=1' 'hid://046d:c21d?serial=A1&interface=0' \
             'evdev://name/Xbox%20360%20Pad' evdev://045e:028e evdev:///dev/input/event3; do
      printf '\x03%s' "$u" >"$corpus/url$((n++))"
    done
    ;;
  # command_auth and lcm_messages write their own seeds (LLVMFuzzerInitialize).
esac

cd "$work"
exec "$binary" -runs="$runs" -seed=1 -max_total_time="${RISE_FUZZ_SECONDS:-50}" -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 -artifact_prefix="$artifacts/" "${extra[@]}" "$corpus"
