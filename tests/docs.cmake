# The manual agrees with the tool: every option `tdf help <command>` shows is in the options table of
# docs/commands/<command>.md (written by scripts/docs-options.py), and every relative link in
# README.md and docs/ leads to a file that exists.
add_test(NAME Docs.options
         COMMAND ${CMAKE_COMMAND} -DTDF=$<TARGET_FILE:tdf> -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DCHECK=options
                 -P ${PROJECT_SOURCE_DIR}/tests/docs/check_docs.cmake)
add_test(NAME Docs.links
         COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DCHECK=links
                 -P ${PROJECT_SOURCE_DIR}/tests/docs/check_docs.cmake)
set_tests_properties(Docs.options Docs.links PROPERTIES LABELS "docs")
