# Multi-part support: the generator of the shipped scenes/two_part_sphere assets (checked against
# the committed files) and tdf_test_segmenter, a protocol test program for the `external` parts
# source (docs/parts-protocol.md).
add_executable(tdf_make_two_part_scene ${PROJECT_SOURCE_DIR}/tools/make_two_part_scene.cpp)
target_link_libraries(tdf_make_two_part_scene PRIVATE tdf_render tdf_warnings)
add_test(NAME TwoPartSceneAssets.MatchGenerator
         COMMAND tdf_make_two_part_scene --check ${PROJECT_SOURCE_DIR}/scenes/two_part_sphere)

add_executable(tdf_test_segmenter ${PROJECT_SOURCE_DIR}/tests/tools/tdf_test_segmenter.cpp)
target_link_libraries(tdf_test_segmenter PRIVATE tdf_io tdf_warnings)
set_target_properties(tdf_test_segmenter PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests/tools)
if(TARGET tdf_parts_tests)
  add_dependencies(tdf_parts_tests tdf_test_segmenter)
  target_compile_definitions(tdf_parts_tests PRIVATE TDF_TEST_SEGMENTER="$<TARGET_FILE:tdf_test_segmenter>")
endif()
