# Generator of the synthetic tactile inputs of issue 28 (tests/unit/tactile_unseen_inputs.h), for
# running `tdf tactile convert` and the measurement script on them by hand.
add_executable(tdf_make_tactile_unseen_inputs ${PROJECT_SOURCE_DIR}/tools/make_tactile_unseen_inputs.cpp)
target_include_directories(tdf_make_tactile_unseen_inputs PRIVATE ${PROJECT_SOURCE_DIR}/tests)
target_link_libraries(tdf_make_tactile_unseen_inputs PRIVATE tdf_tactile tdf_warnings)
