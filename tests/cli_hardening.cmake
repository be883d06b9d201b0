# End-to-end checks of the hardening items (docs/robustness.md "Errors", "Limits"): usage errors, help,
# non-finite options, bounded sizes, output names that must match their format.
add_test(NAME HardeningCli.UsageHelpAndLimits
         COMMAND ${CMAKE_COMMAND} -DTDF=$<TARGET_FILE:tdf> -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
                 -DOUT_DIR=${PROJECT_BINARY_DIR}/test-output/hardening -P ${PROJECT_SOURCE_DIR}/tests/cli/hardening_checks.cmake)
set_tests_properties(HardeningCli.UsageHelpAndLimits PROPERTIES LABELS "unit")

# Replays every committed fuzz regression input through the harness bodies (no libFuzzer).
add_executable(tdf_fuzz_regression_tests ${PROJECT_SOURCE_DIR}/tests/fuzz/fuzz_targets.cpp
                                         ${PROJECT_SOURCE_DIR}/tests/fuzz/fuzz_regression_test.cpp)
target_link_libraries(tdf_fuzz_regression_tests PRIVATE tdf_mesh tdf_tactile tdf_scene tdf_test_common
                      GTest::gtest GTest::gtest_main tdf_warnings)
gtest_discover_tests(tdf_fuzz_regression_tests DISCOVERY_MODE PRE_TEST PROPERTIES LABELS "unit"
                     WORKING_DIRECTORY ${PROJECT_SOURCE_DIR} DISCOVERY_TIMEOUT 60)
