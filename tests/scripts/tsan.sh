#!/usr/bin/env bash
# The servo (hapticut-servo) and its unit tests built with ThreadSanitizer in their
# own build directory (build/tsan): `build` configures and compiles them
# (tests/scripts/setup.sh calls it), `run` runs the unit tests (among them the
# handoffs between the threads, server/tests/handoff_threads_test.cpp), then the
# Python tests with HAPTICUT_SERVO pointing at the servo, and fails on any report
# (tests/run_all.sh calls it).
#
# The Python tests: every servo test file that runs the loop, control/stream, recorder
# and housekeeping threads (and the bridge device's receive thread, the Force Dimension
# device's library calls from the tick and from reconnection, through the DHD stand-in built
# here too, which test_servo_forcedimension.py finds beside the servo, and the OpenHaptics
# device's scheduler callback handing samples and forces to the loop, through the HD
# stand-in's own scheduler thread, test_servo_openhaptics.py), about a minute
# under TSan on 2 cores; left out: test_servo_layout.py (--print-layout, no thread runs),
# test_servo_memory.py (its bounds are on the resident set, which TSan's shadow memory
# multiplies) and test_servo_rightful_client.py (floods the control thread alone, whose
# answers within a second TSan's slowdown would measure instead). Their waits count what the clock-paced threads do in a stretch of time
# (ticks at 1 kHz, frames at the subscribed rate); under TSan a tick computes in
# 50-70 us at p99 (8-9 us without), far inside its 1 ms, with no late tick, so the
# counts are those of the plain runs (40 frames in 0.2 s after the UDP flood, as
# without TSan).
#
# Real time under TSan: the loop still asks for SCHED_FIFO (as in the plain runs),
# and TSan makes mlockall a no-op (it cannot lock its shadow memory), so the servo
# reports "memory: locked" without locking anything; neither changes what is checked.
set -euo pipefail
cd "$(dirname "$0")/../.."
source tools/install_lib.sh  # CMAKE_LAUNCHER_DEFINES: ccache, when installed

case "${1:-run}" in
  build)
    # clang: its TSan runtime comes with libclang-rt-14-dev (setup.sh installs it).
    cmake -S . -B build/tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      "${CMAKE_LAUNCHER_DEFINES[@]}" \
      -DCMAKE_CXX_COMPILER=clang++ -DHAPTICUT_BUILD_TESTS=ON -DHAPTICUT_BUILD_PYTHON=OFF \
      -DCMAKE_CXX_FLAGS="-fsanitize=thread -fno-omit-frame-pointer" \
      -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread" >/dev/null
    cmake --build build/tsan -j 2 --target hapticut-servo hapticut_servo_tests \
      hapticut_dhd_standin hapticut_hd_standin
    ;;
  run)
    tests=(tests/python/test_servo_stream.py tests/python/test_servo_replay.py
      tests/python/test_servo_faults.py tests/python/test_servo_settings.py
      tests/python/test_servo_client_pipelined.py tests/python/test_servo_cli.py
      tests/python/test_servo_devices.py tests/python/test_servo_stiffness_limit.py
      tests/python/test_servo_hostile_client.py tests/python/test_servo_recording_end.py
      tests/python/test_servo_stall.py tests/python/test_servo_device_files.py
      tests/python/test_servo_strict_protocol.py tests/python/test_servo_forcedimension.py
      tests/python/test_servo_load_in_background.py tests/python/test_servo_openhaptics.py)
    reports="$PWD/build/tsan/reports"
    rm -rf "$reports"
    mkdir -p "$reports"
    # Each process writes its reports to reports/tsan.PID and keeps running (a servo
    # exits with 66 where a test may expect 0); the report files are the verdict, so
    # a report fails the run even when every test passed.
    export TSAN_OPTIONS="log_path=$reports/tsan halt_on_error=0 exitcode=66 second_deadlock_stack=1"
    status=0
    build/tsan/server/hapticut_servo_tests --gtest_brief=1 || status=$?
    # The dropped-records test needs a loop that outpaces the writer; under TSan the loop is
    # the slower of the two and drops nothing, so it runs only in the plain pytest phase (the
    # trailer's threads are exercised by the rest of its file here). The flooding client's
    # cut-off needs replies to pile up faster than the kernel's socket buffers take them;
    # under TSan the servo answers too slowly for that within the test's window, so that test
    # too runs in the plain phase (the rest of its file, the same threads, runs here).
    HAPTICUT_SERVO="$PWD/build/tsan/server/hapticut-servo" \
      python3 -m pytest -q -p no:cacheprovider "${tests[@]}" \
      --deselect tests/python/test_servo_recording_end.py::test_the_trailer_counts_the_records_the_loop_dropped \
      --deselect tests/python/test_servo_hostile_client.py::test_a_flooding_client_is_cut_off_and_the_others_are_served \
      || status=$?
    shopt -s nullglob
    found=("$reports"/tsan.*)
    if [ ${#found[@]} -gt 0 ]; then
      cat "${found[@]}"
      echo "tsan: ${#found[@]} process(es) reported (above; in $reports)" >&2
      exit 1
    fi
    exit "$status"
    ;;
  *)
    echo "usage: $0 [build|run]" >&2
    exit 2
    ;;
esac
