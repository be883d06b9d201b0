# `tdf atlas` end to end on a tiny committed mesh (tests/data/atlas): a vertex-coloured PLY cube
# is unwrapped, its colours baked, and the OBJ, MTL, PNG and JSON report written; bad input
# must give the one-line error (printed only by main's error path, which exits with 1).
set(_atlas_out ${PROJECT_BINARY_DIR}/test-scratch/atlas_cli)
add_test(NAME AtlasCli.VertexColouredPlyToObjWithBakedAlbedo
         COMMAND tdf atlas ${PROJECT_SOURCE_DIR}/tests/data/atlas/coloured_cube.ply -o ${_atlas_out}/cube.obj
                 --size 64 --bake-albedo --report ${_atlas_out}/cube.json)
set_tests_properties(AtlasCli.VertexColouredPlyToObjWithBakedAlbedo PROPERTIES LABELS unit
                     PASS_REGULAR_EXPRESSION "6 charts.*overlaps 0, mirrored charts 0, flipped triangles 0, unmapped faces 0")
add_test(NAME AtlasCli.MissingInputFails COMMAND tdf atlas ${_atlas_out}/missing.ply -o ${_atlas_out}/x.obj)
set_tests_properties(AtlasCli.MissingInputFails PROPERTIES LABELS unit
                     PASS_REGULAR_EXPRESSION "tdf atlas: cannot open '.*missing.ply': no such file")
add_test(NAME AtlasCli.SizeOutOfRangeFails
         COMMAND tdf atlas ${PROJECT_SOURCE_DIR}/tests/data/atlas/coloured_cube.ply -o ${_atlas_out}/x.obj
                 --size 8)
set_tests_properties(AtlasCli.SizeOutOfRangeFails PROPERTIES LABELS unit
                     PASS_REGULAR_EXPRESSION "tdf atlas: atlas size 8 is out of range")
