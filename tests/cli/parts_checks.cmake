# Bad multi-part input: one line naming the scene and the key, exit code 1, nothing written.
# Run by ctest (tests/parts_tools.cmake) with -DTDF -DSOURCE_DIR -DOUT_DIR.
cmake_minimum_required(VERSION 3.20)
include(${CMAKE_CURRENT_LIST_DIR}/check_command.cmake)
set(_scene ${SOURCE_DIR}/scenes/two_part_sphere/scene.json)
file(REMOVE_RECURSE ${OUT_DIR})
file(MAKE_DIRECTORY ${OUT_DIR})

check(1 "scene.json: the scene has no 'parts' section" ""
      ${TDF} parts ${SOURCE_DIR}/scenes/pebble_sphere/scene.json -o ${OUT_DIR}/none)
check(1 "parts.list\\[0\\].select: '1' is not a region of the mesh source \\(found: 'base', 'cap'\\)" ""
      ${TDF} parts ${_scene} -o ${OUT_DIR}/select --size 64 parts.source.kind=mesh)
check(1 "parts.source: k is 2 but the albedo has only 1 distinct colour" ""
      ${TDF} parts ${_scene} -o ${OUT_DIR}/k --size 64 parts.source.kind=colour albedo.source=constant parts.source.k=2)
# A label image of the wrong size: the 128 px ribs map over the 256 px albedo.
check(1 "parts.source.image: '.*ribs_normal.png' is 128x128 but the mesh's albedo texture is 256x256" ""
      ${TDF} parts ${_scene} -o ${OUT_DIR}/size --size 64 parts.source.kind=label_image
      parts.source.image=${SOURCE_DIR}/scenes/two_part_sphere/ribs_normal.png)
file(WRITE ${OUT_DIR}/faces_all_zero.txt "")
file(STRINGS ${SOURCE_DIR}/scenes/two_part_sphere/sphere.obj _faces REGEX "^f ")
foreach(_face IN LISTS _faces)
  file(APPEND ${OUT_DIR}/faces_all_zero.txt "0\n")
endforeach()
# A part whose faces do not exist: every face labelled 0, the 'cap' part selects 1.
check(1 "parts.list\\[0\\].select: '1' is not a region of the face_labels source \\(found: '0'\\)" ""
      ${TDF} parts ${_scene} -o ${OUT_DIR}/empty --size 64
      "parts.source={\"kind\":\"face_labels\",\"file\":\"${OUT_DIR}/faces_all_zero.txt\"}")
foreach(_dir none select k size empty)
  if(EXISTS ${OUT_DIR}/${_dir}/two_part_sphere_label_map.png)
    message(FATAL_ERROR "a failed 'tdf parts' left a label map in ${OUT_DIR}/${_dir}")
  endif()
endforeach()

# Issue 23: bad multi-part input to `tdf optimize` on scenes/four_part_sphere (scenes written
# here with absolute paths): one line naming the part (or key) and the scene file, exit 1, and
# nothing in the output folder but the run's lock file (docs/commands/optimize.md).
set(_four ${SOURCE_DIR}/scenes/four_part_sphere)
set(_head "{\"mesh\":\"${_four}/sphere.obj\",\"albedo\":{\"source\":\"image\",\"image\":\"${_four}/albedo.png\"},\"tactile\":{\"images\":[\"${_four}/ribs_normal.png\"]},")
function(part_json out name map select)
  set(${out} "{\"name\":\"${name}\",\"tactile\":{\"images\":[\"${_four}/${map}_normal.png\"]},\"select\":[\"${select}\"]}" PARENT_SCOPE)
endfunction()
function(check_nothing_written dir)
  file(GLOB _left RELATIVE ${dir} ${dir}/*)
  list(REMOVE_ITEM _left .tdf.lock)
  if(_left)
    message(FATAL_ERROR "a failed 'tdf optimize' left ${_left} in ${dir}")
  endif()
endfunction()
# More parts than the label head supports (64).
set(_list "")
foreach(_k RANGE 64)
  part_json(_p "p${_k}" ribs ribs)
  string(APPEND _list "${_p},")
endforeach()
string(REGEX REPLACE ",$" "" _list "${_list}")
file(WRITE ${OUT_DIR}/many.json "${_head}\"parts\":{\"source\":{\"kind\":\"mesh\"},\"list\":[${_list}]}}")
check(1 "many.json.parts: 'list' has 65 parts; at most 64 are supported" "" ${TDF} --quiet optimize ${OUT_DIR}/many.json -o ${OUT_DIR}/many)
check_nothing_written(${OUT_DIR}/many)
# Two parts naming the same material of the mesh.
part_json(_a ribs ribs ribs)
part_json(_b dimples dimples ribs)
file(WRITE ${OUT_DIR}/twice.json "${_head}\"parts\":{\"source\":{\"kind\":\"mesh\"},\"list\":[${_a},${_b}]}}")
check(1 "twice.json.parts: 'ribs' is selected by both 'ribs' and 'dimples'" "" ${TDF} --quiet optimize ${OUT_DIR}/twice.json -o ${OUT_DIR}/twice)
check_nothing_written(${OUT_DIR}/twice)
# A label image with a colour (yellow, the grain band) that no part's select names.
part_json(_a ribs ribs "#ff0000")
part_json(_b dimples dimples "#00ff00")
part_json(_c weave weave "#0000ff")
file(WRITE ${OUT_DIR}/legend.json
     "${_head}\"parts\":{\"source\":{\"kind\":\"label_image\",\"image\":\"${_four}/label_image.png\"},\"list\":[${_a},${_b},${_c}]}}")
check(1 "legend.json: parts: region '#ffff00' \\(25.0 % of the surface\\) is selected by no part" ""
      ${TDF} --quiet optimize ${OUT_DIR}/legend.json -o ${OUT_DIR}/legend)
check_nothing_written(${OUT_DIR}/legend)
# A part whose only face covers no texel of a 16 x 16 atlas (face 0 at the pole).
file(STRINGS ${_four}/labels.txt _labels REGEX "^[a-z]")
list(LENGTH _labels _n)
math(EXPR _n "${_n} - 1")
file(WRITE ${OUT_DIR}/one_face.txt "b\n")
foreach(_i RANGE 1 ${_n})
  file(APPEND ${OUT_DIR}/one_face.txt "a\n")
endforeach()
part_json(_a a ribs a)
part_json(_b b grain b)
file(WRITE ${OUT_DIR}/tiny.json
     "${_head}\"parts\":{\"source\":{\"kind\":\"face_labels\",\"file\":\"${OUT_DIR}/one_face.txt\"},\"list\":[${_a},${_b}]}}")
check(1 "tiny.json: parts.list\\[1\\]: part 'b' has no faces large enough to cover a texel" ""
      ${TDF} --quiet optimize ${OUT_DIR}/tiny.json -o ${OUT_DIR}/tiny export.texture_size=16)
check_nothing_written(${OUT_DIR}/tiny)
