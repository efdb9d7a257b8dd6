# ctest `package_cli_data`: the installed CLI reads its validation scenarios and runs its plot
# script from <prefix>/share/ringtrack, not from the source tree (apps/ringtrack/data_dirs.cpp).
# Run with -DPREFIX= -DWORK_DIR=.
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${PREFIX}/bin/ringtrack benchmark --validation --sensors static
                        --duration 0.5 --quiet --out ${WORK_DIR}
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the installed ringtrack benchmark --validation failed (${rc}): ${err}")
endif()
# One validation scenario by name: it came from share/ringtrack/config/validation/.
file(READ ${WORK_DIR}/results.json results)
if(NOT results MATCHES "v1-plaza-groups")
  message(FATAL_ERROR "${WORK_DIR}/results.json lacks the validation scenarios")
endif()
# The plot needs matplotlib; without it the CLI warns and draws nothing, whatever the paths.
execute_process(COMMAND /usr/bin/python3 -c "import matplotlib, numpy" RESULT_VARIABLE no_plots
                OUTPUT_QUIET ERROR_QUIET)
if(no_plots EQUAL 0 AND NOT EXISTS ${WORK_DIR}/stage_times.png)
  message(FATAL_ERROR "no stage_times.png: the installed CLI did not run its plot script: ${err}")
endif()
