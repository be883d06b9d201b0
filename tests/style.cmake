# Style checks on the sources (label style): no function in src/ longer than 120 lines
# (scripts/function-lengths.py, which names each one that is). The second test runs the same
# script on a fixture whose function has 121 lines and passes only when the script names it with
# its length, so a checker that stopped seeing long functions (or that crashed) fails too.
find_package(Python3 COMPONENTS Interpreter)
if(Python3_Interpreter_FOUND)
  add_test(NAME Style.function_length
           COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/scripts/function-lengths.py --max 120
                   ${PROJECT_SOURCE_DIR}/src)
  add_test(NAME Style.function_length_fails
           COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/scripts/function-lengths.py --max 120
                   ${PROJECT_SOURCE_DIR}/tests/style/too_long.cpp)
  set_tests_properties(Style.function_length_fails PROPERTIES
                       PASS_REGULAR_EXPRESSION "too_long.cpp:8: function 'too_long' is 121 lines")
  set_tests_properties(Style.function_length Style.function_length_fails PROPERTIES LABELS "style")
else()
  message(WARNING "python3 not found: the Style.* tests (function length) are not added")
endif()
