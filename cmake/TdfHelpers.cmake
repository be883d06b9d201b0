# Small helpers so that each folder's CMake stays a few lines.

add_library(tdf_warnings INTERFACE)
target_compile_options(tdf_warnings INTERFACE -Wall -Wextra -Wpedantic -Wshadow -Wno-unused-parameter
                       $<$<BOOL:${TDF_WERROR}>:-Werror>)
if(TDF_SANITIZE)
  # Every target of the build (libraries, tdf, test suites, test helpers and tools) is
  # instrumented, not only those that link tdf_warnings; UB aborts so a test fails on it.
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()

if(TDF_FUZZ)
  # Coverage instrumentation for libFuzzer plus ASan/UBSan in every library; the harnesses
  # (tests/fuzz) link the fuzzer runtime. UB aborts so the fuzzer records it as a crash.
  target_compile_options(tdf_warnings INTERFACE -fsanitize=fuzzer-no-link,address,undefined
                         -fno-sanitize-recover=all -fno-omit-frame-pointer -gline-tables-only)
  target_link_options(tdf_warnings INTERFACE -fsanitize=address,undefined)
endif()

# tdf_add_module(<name> DEPS <targets...>)
# One static library per pipeline stage: sources are src/<name>/*.cpp, public headers
# include/tdf/<name>/*.h. A folder with no sources yet becomes an INTERFACE library.
function(tdf_add_module name)
  cmake_parse_arguments(ARG "" "" "DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB _srcs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/${name}/*.cpp)
  set(_target tdf_${name})
  if(_srcs)
    add_library(${_target} STATIC ${_srcs})
    target_include_directories(${_target} PUBLIC ${PROJECT_SOURCE_DIR}/include)
    target_link_libraries(${_target} PUBLIC ${ARG_DEPS} PRIVATE tdf_warnings ${ARG_PRIVATE_DEPS})
  else()
    add_library(${_target} INTERFACE)
    target_include_directories(${_target} INTERFACE ${PROJECT_SOURCE_DIR}/include)
    target_link_libraries(${_target} INTERFACE ${ARG_DEPS})
  endif()
endfunction()

# tdf_add_test_suite(<module> DEPS <targets...> LABELS <labels...>)
# One gtest executable per module from tests/unit/<module>_*_test.cpp.
function(tdf_add_test_suite module)
  cmake_parse_arguments(ARG "" "COST" "DEPS;LABELS" ${ARGN})
  file(GLOB _srcs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/unit/${module}_*_test.cpp)
  if(NOT _srcs)
    return()
  endif()
  set(_target tdf_${module}_tests)
  add_executable(${_target} ${_srcs})
  target_link_libraries(${_target} PRIVATE ${ARG_DEPS} tdf_test_common GTest::gtest GTest::gtest_main
                        tdf_warnings)
  if(NOT ARG_LABELS)
    set(ARG_LABELS unit)
  endif()
  # gtest_discover_tests' PRE_TEST mode (CMake 3.25) drops the escaping of a list inside
  # PROPERTIES, so a suite gets ONE label joining its tiers ("unit_gradcheck"); `ctest -L` takes a
  # regular expression, so `-L unit` and `-L gradcheck` both select it.
  string(REPLACE ";" "_" _labels "${ARG_LABELS}")
  # COST: ctest -j starts the costliest tests first (the CI's fresh build has no measured costs),
  # so that no long test starts last and runs alone.
  if(NOT ARG_COST)
    set(ARG_COST 1)
  endif()
  gtest_discover_tests(${_target} DISCOVERY_MODE PRE_TEST PROPERTIES LABELS "${_labels}" COST ${ARG_COST}
                       WORKING_DIRECTORY ${PROJECT_SOURCE_DIR} DISCOVERY_TIMEOUT 60)
endfunction()
