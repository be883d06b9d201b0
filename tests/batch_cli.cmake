# `tdf batch` end to end with the real tdf on tiny jobs: the local engine (always) and a real
# single-node Slurm started and stopped by the test (skipped when slurm-wlm/munge are missing or
# not root). Daemon state stays under the build tree.
foreach(_engine local slurm)
  add_test(NAME BatchCli.${_engine}
           COMMAND bash ${PROJECT_SOURCE_DIR}/tests/batch/batch_test.sh ${_engine} $<TARGET_FILE:tdf>
                   ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}/test-scratch/batch_cli_${_engine})
  set_tests_properties(BatchCli.${_engine} PROPERTIES LABELS unit SKIP_RETURN_CODE 77 TIMEOUT 900 COST 60)
endforeach()

# 20 tiny jobs with injected bad inputs and self-kills: failure classes, retries, --max-failures,
# --timeout and bad manifests (docs/commands/batch.md).
add_test(NAME BatchCli.retries
         COMMAND bash ${PROJECT_SOURCE_DIR}/tests/batch/batch_retry_test.sh $<TARGET_FILE:tdf>
                 ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}/test-scratch/batch_cli_retries)
set_tests_properties(BatchCli.retries PROPERTIES LABELS unit TIMEOUT 600 COST 55)
