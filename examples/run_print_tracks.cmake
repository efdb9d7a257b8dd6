# ctest `example_print_tracks`: simulates three seconds of the empty field (six walkers, static
# sensor) with the CLI and runs print_tracks on the sequence folder and its poses. Run with
# -DCLI= -DEXAMPLE= -DWORK_DIR=.
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CLI} simulate empty-field --duration 3 --seed 1 --out ${WORK_DIR}/seq
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "ringtrack simulate failed (${rc}): ${err}")
endif()
execute_process(COMMAND ${EXAMPLE} ${WORK_DIR}/seq ${WORK_DIR}/seq/poses.txt
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "print_tracks failed (${rc}): ${err}")
endif()
# One line per scan, and by the last scans the walkers' confirmed tracks.
string(REGEX MATCHALL "scan at [0-9.]+ s: [0-9]+ detections\n" scan_lines "${out}")
list(LENGTH scan_lines scans)
if(NOT scans EQUAL 30)
  message(FATAL_ERROR "print_tracks printed ${scans} scans, expected 30:\n${out}")
endif()
if(NOT out MATCHES "  track [0-9]+ at \\(-?[0-9.]+, -?[0-9.]+, -?[0-9.]+\\) m, [0-9.]+ m/s")
  message(FATAL_ERROR "print_tracks printed no track:\n${out}")
endif()
