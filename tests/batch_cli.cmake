# `tdf batch` end to end with the real tdf on tiny jobs: the local engine (always) and a real
# single-node Slurm started and stopped by the test (skipped when slurm-wlm/munge are missing or
# not root). Daemon state stays under the build tree.
foreach(_engine local slurm)
  add_test(NAME BatchCli.${_engine}
           COMMAND bash ${PROJECT_SOURCE_DIR}/tests/batch/batch_test.sh ${_engine} $<TARGET_FILE:tdf>
                   ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}/test-scratch/batch_cli_${_engine})
  set_tests_properties(BatchCli.${_engine} PROPERTIES LABELS unit SKIP_RETURN_CODE 77 TIMEOUT 900)
endforeach()
