# HTML reports opened in a real headless browser (issue 16), label `browser`, and the Khronos glTF
# validator on the exported .glb of every shipped scene, label `gltf`. Both need what
# scripts/install-deps.sh installs: Debian's chromium, node, and `npm ci` in web/ (three.js,
# puppeteer-core, pngjs, gltf-validator). Without them the tests are registered as skipped.
#
# Fixtures: a tiny `tdf optimize` of pebble_sphere (its report page and .glb), a `tdf compare
# --html` of two golden renders, a batch index with hand-made rows (report_batch_demo); then
# web/tests/check_pages.js opens the three pages from file:// and checks them.
add_executable(report_batch_demo ${PROJECT_SOURCE_DIR}/tests/tools/report_batch_demo.cpp)
target_link_libraries(report_batch_demo PRIVATE tdf_report tdf_warnings)
set_target_properties(report_batch_demo PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests/tools)

find_program(TDF_NODE node)
find_program(TDF_CHROMIUM NAMES chromium chromium-browser)
set(_web ${PROJECT_SOURCE_DIR}/web)
set(_out ${PROJECT_BINARY_DIR}/test-scratch/browser)
set(_missing "")
if(NOT TDF_NODE)
  string(APPEND _missing " node")
endif()
if(NOT TDF_CHROMIUM)
  string(APPEND _missing " chromium")
endif()
if(NOT EXISTS ${_web}/node_modules/puppeteer-core OR NOT EXISTS ${_web}/node_modules/gltf-validator
   OR NOT EXISTS ${_web}/node_modules/three)
  string(APPEND _missing " web/node_modules (npm ci in web/)")
endif()

if(_missing)
  foreach(_t ReportBrowser.Pages GltfValidator.ShippedScenes)
    add_test(NAME ${_t} COMMAND ${CMAKE_COMMAND} -E echo "skipped: missing${_missing}; run scripts/install-deps.sh")
    set_tests_properties(${_t} PROPERTIES LABELS browser SKIP_REGULAR_EXPRESSION "skipped:")
  endforeach()
  return()
endif()

# Small enough for CI: 4 iterations at 64 px, 256 px maps, 4 turntable views at 128 px.
set(_tiny optimize.iterations=4 optimize.init_iterations=2 optimize.resolution=64 optimize.patch_resolution=64
    optimize.batch_size=1 optimize.patch_batch_size=1 optimize.held_out_views=1 optimize.held_out_patches=1
    export.texture_size=256 export.turntable_views=4 export.turntable_resolution=128)

add_test(NAME ReportBrowser.OptimizeRun
         COMMAND tdf --quiet optimize ${PROJECT_SOURCE_DIR}/scenes/pebble_sphere/scene.json -o ${_out}/run ${_tiny})
set_tests_properties(ReportBrowser.OptimizeRun PROPERTIES LABELS browser FIXTURES_SETUP report_pages COST 64)

# Two golden views: every pass differs, so the page shows failures and heatmaps (exit 1 = fail).
add_test(NAME ReportBrowser.ComparePage
         COMMAND sh -c "\"$0\" compare \"$1\" \"$2\" --erode-mask 1 --html \"$3\" > /dev/null; test $? = 1"
                 $<TARGET_FILE:tdf> ${PROJECT_SOURCE_DIR}/reference/golden/pebble_visualizer/view_000.exr
                 ${PROJECT_SOURCE_DIR}/reference/golden/pebble_visualizer/view_001.exr ${_out}/compare/compare.html)
set_tests_properties(ReportBrowser.ComparePage PROPERTIES LABELS browser FIXTURES_SETUP report_pages COST 64)

add_test(NAME ReportBrowser.BatchIndex
         COMMAND report_batch_demo ${_out}/batch ${_out}/run/pebble_sphere_report.html
                 ${_out}/run/turntable/albedo_000.png)
set_tests_properties(ReportBrowser.BatchIndex PROPERTIES LABELS browser FIXTURES_SETUP report_pages COST 64
                     DEPENDS ReportBrowser.OptimizeRun)

# Every shipped scene's exported .glb through the Khronos validator: 0 errors, 0 warnings.
set(_glbs "")
set(_scene_pages "")
file(GLOB _scenes RELATIVE ${PROJECT_SOURCE_DIR}/scenes CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/scenes/*/scene.json)
foreach(_scene_file ${_scenes})
  get_filename_component(_scene ${_scene_file} DIRECTORY)
  file(READ ${PROJECT_SOURCE_DIR}/scenes/${_scene_file} _scene_text)
  if(_scene_text MATCHES "shared/data" AND NOT EXISTS ${PROJECT_SOURCE_DIR}/../shared/data)
    message(STATUS "glTF validator: scene ${_scene} skipped (its data is in ../shared/data, absent)")
    continue()
  endif()
  add_test(NAME GltfValidator.Export.${_scene}
           COMMAND tdf --quiet optimize ${PROJECT_SOURCE_DIR}/scenes/${_scene_file} -o ${_out}/glb/${_scene} ${_tiny}
                   export.turntable_views=0)
  set_tests_properties(GltfValidator.Export.${_scene} PROPERTIES LABELS gltf FIXTURES_SETUP gltf_exports COST 64)
  list(APPEND _glbs ${_out}/glb/${_scene}/${_scene}.glb)
  list(APPEND _scene_pages ${_out}/glb/${_scene}/${_scene}_report.html)
endforeach()
add_test(NAME GltfValidator.ShippedScenes COMMAND ${TDF_NODE} ${_web}/tests/validate_gltf.js ${_glbs})
set_tests_properties(GltfValidator.ShippedScenes PROPERTIES LABELS gltf FIXTURES_REQUIRED gltf_exports
                     PASS_REGULAR_EXPRESSION " 0 failed")

# The pages, opened in Chromium; the shipped scenes' pages (3D view only, no turntables) too, so
# the silhouette check covers real meshes (spot, mug, avocado) as well as the sphere.
add_test(NAME ReportBrowser.Pages
         COMMAND ${TDF_NODE} ${_web}/tests/check_pages.js --chromium ${TDF_CHROMIUM} --tdf $<TARGET_FILE:tdf>
                 --out ${_out}/screenshots ${_out}/run/pebble_sphere_report.html ${_out}/compare/compare.html
                 ${_out}/batch/index.html ${_scene_pages})
# COST: ctest -j starts costlier tests first. The page check (about 60 s) waits for its fixtures'
# exports, so both go first, and the check does not run alone at the end.
set_tests_properties(ReportBrowser.Pages PROPERTIES LABELS browser COST 63 FIXTURES_REQUIRED "report_pages;gltf_exports"
                     PASS_REGULAR_EXPRESSION " 0 failed" TIMEOUT 600)

