# By-hand check that a multi-part export opens in Blender with one material slot per part (not
# run by CI; Blender 3.4 from Debian). Imports each file given (.glb / .gltf or .obj) into an
# empty scene and prints, per file, the materials of the imported mesh objects and how many
# faces use each; exits 1 when a file's slots are not the expected names.
#
#   blender -b --factory-startup --python tools/blender_parts_check.py -- PARTS FILE...
#   (PARTS: comma-separated part names, e.g. ribs,dimples,weave,grain)
import bpy, sys
import numpy

# Debian's Blender 3.4 glTF importer uses numpy.bool, which the system's numpy 1.24 removed.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

args = sys.argv[sys.argv.index("--") + 1:]
expected = args[0].split(",")
failed = 0
for path in args[1:]:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.endswith((".glb", ".gltf")):
        bpy.ops.import_scene.gltf(filepath=path)
    else:
        bpy.ops.wm.obj_import(filepath=path)
    faces = {}
    for obj in bpy.data.objects:
        if obj.type != "MESH":
            continue
        for poly in obj.data.polygons:
            slot = obj.material_slots[poly.material_index] if obj.material_slots else None
            name = slot.material.name if slot and slot.material else "(none)"
            faces[name] = faces.get(name, 0) + 1
    names = sorted(faces)
    ok = names == sorted(expected)
    failed += not ok
    print("%s %s: %d material slot(s) in use: %s" % ("PASS" if ok else "FAIL", path, len(names),
          ", ".join("%s (%d faces)" % (n, faces[n]) for n in names)))
sys.exit(1 if failed else 0)
