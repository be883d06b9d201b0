# End-to-end checks of usage errors, help, non-finite options, limits and output names.
# Run by ctest (tests/cli_hardening.cmake) with -DTDF -DSOURCE_DIR -DOUT_DIR.
cmake_minimum_required(VERSION 3.20)
set(_scene ${SOURCE_DIR}/scenes/pebble_sphere/scene.json)
set(_normal ${SOURCE_DIR}/scenes/pebble_sphere/tactile_normal.png)
file(REMOVE_RECURSE ${OUT_DIR})
file(MAKE_DIRECTORY ${OUT_DIR})

include(${CMAKE_CURRENT_LIST_DIR}/check_command.cmake)

# Help: the command list, nested commands, negated flags without "{false}".
check(0 "" "render.*compare.*tactile.*atlas.*optimize" ${TDF} help)
check(0 "" "render.*compare.*tactile.*atlas.*optimize" ${TDF})
check(0 "" "--steps-png.*--no-tileable" ${TDF} help tactile convert)
if(LAST_STDOUT MATCHES "\\{false\\}")
  message(FATAL_ERROR "`tdf help tactile convert` shows a flag default in braces:\n${LAST_STDOUT}")
endif()
check(0 "" "--patch-size" ${TDF} help tactile patch)
check(1 "^tdf help: .*no command 'nosuch'" "" ${TDF} help nosuch)
check(1 "^tdf help: 'tdf tactile' has no command 'bogus'" "" ${TDF} help tactile bogus)

# Usage errors: one line naming the command, exit 1 (docs/robustness.md "Errors"), not CLI11's 105-109.
check(1 "^tdf render: .*--bogus" "" ${TDF} render ${_scene} -o ${OUT_DIR}/x --bogus)
check(1 "^tdf render: .*required" "" ${TDF} render)
# --strength also accepts "auto" (issue 11): its own check names the option on one line.
check(1 "^tdf tactile: --strength: must be auto or a finite number > 0, got 1e400 \\(see `tdf help tactile normal`\\)$" "" ${TDF} tactile normal ${_normal} -o ${OUT_DIR}/n.png --strength 1e400)
check(1 "^tdf render: --threads: Value -3 not in range 0 to 4096" "" ${TDF} --threads -3 render ${_scene} -o ${OUT_DIR}/x)

# Non-finite options are errors naming the option.
check(1 "^tdf tactile: --strength: must be (auto or )?a finite number( > 0)?, got nan" "" ${TDF} tactile normal ${_normal} -o ${OUT_DIR}/n.png --strength nan)
check(1 "^tdf tactile: --mm-per-pixel: must be a finite number, got nan" "" ${TDF} tactile height ${_normal} -o ${OUT_DIR}/h.exr --mm-per-pixel nan)
check(1 "^tdf tactile: --mm-per-pixel: (must be a finite number, got inf|Value inf not in range)" "" ${TDF} tactile height ${_normal} -o ${OUT_DIR}/h.exr --mm-per-pixel inf)

# Bounded sizes, checked before any work.
check(1 "^tdf render: --turntable" "" ${TDF} render ${_scene} -o ${OUT_DIR}/x --turntable 100000000)
check(1 "^tdf render: .*scene.json.views: 100000002 views in all .* over the limit of 10000" "" ${TDF} render ${_scene} -o ${OUT_DIR}/x views.random.count=100000000)
check(1 "^tdf render: .*image 16384x16384 at ssaa 4 .* over the limit of 16384" "" ${TDF} render ${_scene} -o ${OUT_DIR}/x ssaa=4 image.width=16384 image.height=16384)
check(1 "^tdf tactile: --patch-size" "" ${TDF} tactile patch ${_normal} -o ${OUT_DIR}/p.exr --patch-size 100000)
check(1 "^tdf tactile: --size" "" ${TDF} tactile quilt ${_normal} -o ${OUT_DIR}/q.exr --size 1000000)

# Scene values: full unsigned 64-bit seeds, out-of-range numbers name the key.
check(1 "^tdf render: .*'seed' must be an integer in \\[0, 18446744073709551615\\], got -1" "" ${TDF} render ${_scene} -o ${OUT_DIR}/x seed=-1)
check(1 "^tdf render: .*override 'ssaa=1e999'" "" ${TDF} render ${_scene} -o ${OUT_DIR}/x ssaa=1e999)
check(0 "" "" ${TDF} -q render ${_scene} -o ${OUT_DIR}/seed seed=18446744073709551615 image.width=8 image.height=8)
file(READ ${OUT_DIR}/seed/resolved_scene.json _resolved)
if(NOT _resolved MATCHES "\"seed\": 18446744073709551615")
  message(FATAL_ERROR "resolved_scene.json does not keep the seed 2^64-1:\n${_resolved}")
endif()
file(WRITE ${OUT_DIR}/dup.json "{\"mesh\": \"${SOURCE_DIR}/scenes/pebble_sphere/sphere.obj\", \"ssaa\": 1, \"ssaa\": 2}")
check(1 "^tdf render: .*dup.json: duplicate key 'ssaa'" "" ${TDF} render ${OUT_DIR}/dup.json -o ${OUT_DIR}/x)
file(WRITE ${OUT_DIR}/huge.json "{\"mesh\": \"m.obj\", \"ssaa\": 1e999}")
check(1 "^tdf render: .*huge.json: invalid JSON: number overflow" "" ${TDF} render ${OUT_DIR}/huge.json -o ${OUT_DIR}/x)

# Output names say the format; a folder is not a file name.
check(1 "^tdf compare: .*d.png: --diff .* must be named .exr" "" ${TDF} compare ${_normal} ${_normal} --diff ${OUT_DIR}/d.png)
check(1 "^tdf tactile: .*n.jpg: a normal map \\(-o\\) must be named .png, .exr" "" ${TDF} -q tactile normal ${_normal} -o ${OUT_DIR}/n.jpg)
check(1 "^tdf tactile: .*c.jpeg: a normal map \\(-o\\) must be named .png, .exr" "" ${TDF} -q tactile convert ${_normal} -o ${OUT_DIR}/c.jpeg)
if(EXISTS ${OUT_DIR}/n.jpg)
  message(FATAL_ERROR "a refused n.jpg was written")
endif()
file(MAKE_DIRECTORY ${OUT_DIR}/folder.png)
check(1 "^tdf tactile: cannot write '.*folder.png': it is a folder" "" ${TDF} -q tactile normal ${_normal} -o ${OUT_DIR}/folder.png)
