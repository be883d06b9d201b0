# tdf_test_refiner: a protocol test program for the "external" guidance backend. It implements the
# file protocol of docs/guidance-protocol.md with a fixed, deterministic transform (no model), and
# can fail on purpose, so the plumbing is tested end to end.
add_executable(tdf_test_refiner ${PROJECT_SOURCE_DIR}/tests/tools/tdf_test_refiner.cpp)
target_link_libraries(tdf_test_refiner PRIVATE tdf_io tdf_warnings)
set_target_properties(tdf_test_refiner PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests/tools)
if(TARGET tdf_guidance_tests)
  add_dependencies(tdf_guidance_tests tdf_test_refiner)
  target_compile_definitions(tdf_guidance_tests PRIVATE TDF_TEST_REFINER="$<TARGET_FILE:tdf_test_refiner>")
endif()
