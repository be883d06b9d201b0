# Render regression suite (label `render`): golden EXRs in reference/golden/<case>/ re-rendered
# by `tdf render` and compared with `tdf compare` under the case's tolerances.
#   ctest --test-dir build -L render                              run it
#   TDF_UPDATE_REFERENCES=1 ctest --test-dir build -L render      rewrite the goldens on purpose
# Also builds and checks the generator of the shipped pebble_sphere assets, and runs the CLI
# end-to-end checks (tests/render/cli_checks.cmake).

add_executable(tdf_make_pebble_sphere ${PROJECT_SOURCE_DIR}/tools/make_pebble_sphere.cpp)
target_link_libraries(tdf_make_pebble_sphere PRIVATE tdf_render tdf_warnings)
add_test(NAME PebbleSphereAssets.MatchGenerator
         COMMAND tdf_make_pebble_sphere --check ${PROJECT_SOURCE_DIR}/scenes/pebble_sphere)
set_tests_properties(PebbleSphereAssets.MatchGenerator PROPERTIES LABELS "render")
# scenes/dark_bottle and scenes/painted_torus (issue 29: dark and saturated base colours).
add_executable(tdf_make_colour_scenes ${PROJECT_SOURCE_DIR}/tools/make_colour_scenes.cpp)
target_link_libraries(tdf_make_colour_scenes PRIVATE tdf_render tdf_warnings)
add_test(NAME ColourScenesAssets.MatchGenerator
         COMMAND tdf_make_colour_scenes --check ${PROJECT_SOURCE_DIR}/scenes)
set_tests_properties(ColourScenesAssets.MatchGenerator PROPERTIES LABELS "render")

file(GLOB _golden_cases CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/reference/golden/*/case.json)
foreach(_case_file ${_golden_cases})
  get_filename_component(_case_dir ${_case_file} DIRECTORY)
  get_filename_component(_case ${_case_dir} NAME)
  add_test(NAME RenderGolden.${_case}
           COMMAND ${CMAKE_COMMAND} -DTDF=$<TARGET_FILE:tdf> -DCASE_DIR=${_case_dir}
                   -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DOUT_DIR=${PROJECT_BINARY_DIR}/test-output/golden/${_case}
                   -P ${PROJECT_SOURCE_DIR}/tests/render/golden_case.cmake)
  set_tests_properties(RenderGolden.${_case} PROPERTIES LABELS "render")
endforeach()

add_test(NAME RenderCli.ExitCodesAndOutputs
         COMMAND ${CMAKE_COMMAND} -DTDF=$<TARGET_FILE:tdf> -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
                 -DOUT_DIR=${PROJECT_BINARY_DIR}/test-output/cli -P ${PROJECT_SOURCE_DIR}/tests/render/cli_checks.cmake)
set_tests_properties(RenderCli.ExitCodesAndOutputs PROPERTIES LABELS "render")
