# End-to-end checks of `tdf render` and `tdf compare` (exit codes, one-line errors, outputs).
# Run by ctest with -DTDF -DSOURCE_DIR -DOUT_DIR.
cmake_minimum_required(VERSION 3.20)
set(_scene ${SOURCE_DIR}/scenes/pebble_sphere/scene.json)
file(REMOVE_RECURSE ${OUT_DIR})

include(${CMAKE_CURRENT_LIST_DIR}/../cli/check_command.cmake)

# Bad input: one line "tdf render: ...", exit 1.
check(1 "^tdf render: .*unknown pass 'glossy'" "" ${TDF} render ${_scene} -o ${OUT_DIR}/bad "passes=[\"glossy\"]")
check(1 "^tdf render: .*image size 0x" "" ${TDF} render ${_scene} -o ${OUT_DIR}/bad image.width=0)
check(1 "^tdf render: .*nothere.json" "" ${TDF} render ${OUT_DIR}/nothere.json -o ${OUT_DIR}/bad)
check(1 "^tdf render: .*missing.obj" "" ${TDF} render ${_scene} -o ${OUT_DIR}/bad mesh=missing.obj)
check(1 "^tdf render: .*unknown key" "" ${TDF} render ${_scene} -o ${OUT_DIR}/bad colour=red)

# Turntable: N views plus the resolved scene.
check(0 "" "" ${TDF} -q render ${_scene} -o ${OUT_DIR}/turn --turntable 3 image.width=32 image.height=24 --png)
foreach(_f view_000.exr view_001.exr view_002.exr resolved_scene.json view_002_lambertian.png)
  if(NOT EXISTS ${OUT_DIR}/turn/${_f})
    message(FATAL_ERROR "tdf render --turntable 3 did not write ${_f}")
  endif()
endforeach()
if(EXISTS ${OUT_DIR}/turn/view_003.exr)
  message(FATAL_ERROR "--turntable 3 wrote a fourth view")
endif()
# The resolved scene renders the same images again.
check(0 "" "" ${TDF} -q render ${OUT_DIR}/turn/resolved_scene.json -o ${OUT_DIR}/again)

# compare: 0 pass, 1 fail, 2 size mismatch, 1 unreadable.
check(0 "" "" ${TDF} compare ${OUT_DIR}/turn/view_001.exr ${OUT_DIR}/again/view_001.exr)
check(1 "" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/turn/view_001.exr --diff ${OUT_DIR}/diff.exr)
if(NOT EXISTS ${OUT_DIR}/diff.exr)
  message(FATAL_ERROR "tdf compare --diff did not write the difference image")
endif()
check(0 "" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/turn/view_001.exr --fail 2 --hardfail 10)
check(0 "" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/turn/view_001.exr --failpercent 100)
check(0 "" "" ${TDF} -q render ${_scene} -o ${OUT_DIR}/big image.width=40 image.height=24)
check(2 "is 32x24 but" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/big/view_000.exr)
check(1 "^tdf compare: .*absent.exr" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/absent.exr)

# compare never passes by mistake: option values are validated (NaN used to pass every pair).
check(1 "^tdf compare: --fail:? must be a finite number" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/turn/view_001.exr --fail nan)
check(1 "^tdf compare: --failpercent must be" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/turn/view_001.exr --failpercent 101)
check(1 "^tdf compare: --hardfail:? must be" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/turn/view_001.exr --hardfail nan)
check(1 "^tdf compare: --erode-mask must be" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/turn/view_001.exr --erode-mask -1)
check(1 "^tdf compare: --diff-scale must be" "" ${TDF} compare ${OUT_DIR}/turn/view_000.exr ${OUT_DIR}/turn/view_001.exr --diff-scale 0)
# JSON of identical images: PSNR null with psnr_infinite, never the string "inf".
execute_process(COMMAND ${TDF} compare ${OUT_DIR}/turn/view_001.exr ${OUT_DIR}/again/view_001.exr --json
                RESULT_VARIABLE _rc OUTPUT_VARIABLE _json)
string(JSON _psnr_type TYPE "${_json}" overall psnr)
string(JSON _mean_type TYPE "${_json}" overall mean_error)
string(JSON _infinite GET "${_json}" overall psnr_infinite)
if(NOT _rc EQUAL 0 OR NOT _psnr_type STREQUAL "NULL" OR NOT _mean_type STREQUAL "NUMBER" OR NOT _infinite)
  message(FATAL_ERROR "compare --json of identical images: rc ${_rc}, psnr ${_psnr_type}, mean ${_mean_type}\n${_json}")
endif()
if(_json MATCHES "\"inf\"")
  message(FATAL_ERROR "compare --json printed the string \"inf\":\n${_json}")
endif()

# Folders: pairs by relative path; missing / extra files fail unless allowed; --renderer raster.
check(0 "" "" ${TDF} -q render ${_scene} -o ${OUT_DIR}/raster --turntable 3 image.width=32 image.height=24 --renderer raster)
check(1 "^tdf render: .*renderer" "" ${TDF} render ${_scene} -o ${OUT_DIR}/bad renderer=gpu)
check(0 "" "" ${TDF} compare ${OUT_DIR}/turn ${OUT_DIR}/again --allow-extra --allow-missing)
check(1 "" "" ${TDF} compare ${OUT_DIR}/turn ${OUT_DIR}/again)
check(0 "" "" ${TDF} compare ${OUT_DIR}/turn ${OUT_DIR}/raster --allow-missing --erode-mask 1 --fail 0.004 --failpercent 0.5 --hardfail 0.2)
check(1 "" "" ${TDF} compare ${OUT_DIR}/turn ${OUT_DIR}/raster --allow-missing --diff ${OUT_DIR}/raster_diffs)
if(NOT EXISTS ${OUT_DIR}/raster_diffs/view_000.diff.exr)
  message(FATAL_ERROR "tdf compare --diff on folders did not write raster_diffs/view_000.diff.exr")
endif()
check(1 "must both be folders" "" ${TDF} compare ${OUT_DIR}/turn ${OUT_DIR}/turn/view_000.exr)

# Re-rendering fewer views (and no PNGs) into an old folder clears the stale views and says so;
# the completion record is written last.
check(0 "" "" ${TDF} -q render ${_scene} -o ${OUT_DIR}/fewer --turntable 3 image.width=16 image.height=16 --png)
execute_process(COMMAND ${TDF} render ${_scene} -o ${OUT_DIR}/fewer --turntable 2 image.width=16 image.height=16
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT err MATCHES "removed [0-9]+ file\\(s\\) of an earlier render")
  message(FATAL_ERROR "re-render with fewer views: exit ${rc}, no notice of the stale views:\n${err}")
endif()
foreach(_f view_002.exr view_000_lambertian.png view_002_lambertian.png)
  if(EXISTS ${OUT_DIR}/fewer/${_f})
    message(FATAL_ERROR "stale ${_f} left after re-rendering 2 views without --png")
  endif()
endforeach()
foreach(_f view_000.exr view_001.exr render_complete.json)
  if(NOT EXISTS ${OUT_DIR}/fewer/${_f})
    message(FATAL_ERROR "re-render did not write ${_f}")
  endif()
endforeach()
