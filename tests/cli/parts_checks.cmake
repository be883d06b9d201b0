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
