# Multi-part support: the generators of the shipped scenes/two_part_sphere and four_part_sphere assets (checked against
# the committed files) and tdf_test_segmenter, a protocol test program for the `external` parts
# source (docs/parts-protocol.md).
add_executable(tdf_make_two_part_scene ${PROJECT_SOURCE_DIR}/tools/make_two_part_scene.cpp)
target_link_libraries(tdf_make_two_part_scene PRIVATE tdf_render tdf_warnings)
add_test(NAME TwoPartSceneAssets.MatchGenerator
         COMMAND tdf_make_two_part_scene --check ${PROJECT_SOURCE_DIR}/scenes/two_part_sphere)
add_executable(tdf_make_four_part_scene ${PROJECT_SOURCE_DIR}/tools/make_four_part_scene.cpp)
target_link_libraries(tdf_make_four_part_scene PRIVATE tdf_render tdf_warnings)
add_test(NAME FourPartSceneAssets.MatchGenerator
         COMMAND tdf_make_four_part_scene --check ${PROJECT_SOURCE_DIR}/scenes/four_part_sphere)

add_executable(tdf_test_segmenter ${PROJECT_SOURCE_DIR}/tests/tools/tdf_test_segmenter.cpp)
target_link_libraries(tdf_test_segmenter PRIVATE tdf_io tdf_warnings)
set_target_properties(tdf_test_segmenter PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests/tools)
if(TARGET tdf_parts_tests)
  add_dependencies(tdf_parts_tests tdf_test_segmenter)
  target_compile_definitions(tdf_parts_tests PRIVATE TDF_TEST_SEGMENTER="$<TARGET_FILE:tdf_test_segmenter>")
endif()

# `tdf parts` end to end on the shipped two-part scene, and the one-line errors of bad input.
set(_parts_out ${PROJECT_BINARY_DIR}/test-scratch/parts_cli)
add_test(NAME PartsCli.TwoPartSphereWritesLabelMapMasksAndReport
         COMMAND tdf parts ${PROJECT_SOURCE_DIR}/scenes/two_part_sphere/scene.json -o ${_parts_out} --size 256)
set_tests_properties(PartsCli.TwoPartSphereWritesLabelMapMasksAndReport PROPERTIES LABELS unit
                     PASS_REGULAR_EXPRESSION "0 cap +42\\.[0-9]+ %.*1 base +57\\.[0-9]+ %.*wrote .*two_part_sphere_label_map.png")
# Bad input: exit code 1 and one line each (a PASS_REGULAR_EXPRESSION alone ignores the exit code).
add_test(NAME PartsCli.BadInputGivesOneLineAndExitCode1
         COMMAND ${CMAKE_COMMAND} -DTDF=$<TARGET_FILE:tdf> -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
                 -DOUT_DIR=${PROJECT_BINARY_DIR}/test-output/parts_checks -P ${PROJECT_SOURCE_DIR}/tests/cli/parts_checks.cmake)
set_tests_properties(PartsCli.BadInputGivesOneLineAndExitCode1 PROPERTIES LABELS unit)
