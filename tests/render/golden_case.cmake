# One golden-image case: re-render reference/golden/<case>/case.json's scene with `tdf render`
# and compare every view with `tdf compare` under the case's tolerance.
# (Not in tests/ itself: tests/CMakeLists.txt includes every tests/*.cmake.)
# Run by ctest (tests/render_goldens.cmake) with -DTDF -DCASE_DIR -DSOURCE_DIR -DOUT_DIR.
# With the environment variable TDF_UPDATE_REFERENCES=1 the new renders replace the goldens.
cmake_minimum_required(VERSION 3.20)

file(READ ${CASE_DIR}/case.json _case)
string(JSON _scene GET "${_case}" scene)
string(JSON _overrides_len LENGTH "${_case}" overrides)
set(_overrides)
if(_overrides_len GREATER 0)
  math(EXPR _last "${_overrides_len} - 1")
  foreach(_i RANGE ${_last})
    string(JSON _o GET "${_case}" overrides ${_i})
    list(APPEND _overrides "${_o}")
  endforeach()
endif()
foreach(_key fail failpercent hardfail erode_mask)
  string(JSON _tol_${_key} GET "${_case}" tolerance ${_key})
endforeach()

file(REMOVE_RECURSE ${OUT_DIR})
execute_process(COMMAND ${TDF} --quiet render ${SOURCE_DIR}/${_scene} -o ${OUT_DIR} ${_overrides}
                RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "tdf render failed (${_rc}) for ${CASE_DIR}")
endif()
file(GLOB _new RELATIVE ${OUT_DIR} ${OUT_DIR}/view_*.exr)
file(GLOB _ref RELATIVE ${CASE_DIR} ${CASE_DIR}/view_*.exr)

if("$ENV{TDF_UPDATE_REFERENCES}" STREQUAL "1")
  foreach(_f ${_ref})
    file(REMOVE ${CASE_DIR}/${_f})
  endforeach()
  foreach(_f ${_new})
    file(COPY ${OUT_DIR}/${_f} DESTINATION ${CASE_DIR})
  endforeach()
  message(STATUS "updated ${CASE_DIR} with ${_new}; review the diff before committing")
  return()
endif()

if(NOT _new STREQUAL _ref)
  message(FATAL_ERROR "views differ: rendered [${_new}], reference [${_ref}] in ${CASE_DIR}")
endif()
set(_failed)
foreach(_f ${_ref})
  string(REPLACE ".exr" ".diff.exr" _diff ${_f})
  execute_process(COMMAND ${TDF} compare ${CASE_DIR}/${_f} ${OUT_DIR}/${_f} --fail ${_tol_fail}
                          --failpercent ${_tol_failpercent} --hardfail ${_tol_hardfail}
                          --erode-mask ${_tol_erode_mask} --diff ${OUT_DIR}/${_diff}
                  RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    list(APPEND _failed "${_f} (new render and |diff| x16 in ${OUT_DIR})")
  endif()
endforeach()
if(_failed)
  message(FATAL_ERROR "golden mismatch: ${_failed}")
endif()
