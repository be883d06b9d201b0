# By-hand check of an exported asset's relief in Blender (not run by CI; Blender 3.4 from Debian:
# `apt-get install -y blender`). Imports an OBJ or GLB, replaces each material's output by the
# world-space shading normal its normal map produces (as emission, n / 2 + 1/2), renders it
# orthographically from -Y (Blender's view of glTF/OBJ +Z) with Cycles, and prints the mean
# normal over the left and right halves of the picture.
#
#   blender -b --factory-startup --python tools/blender_relief_check.py -- ASSET.glb OUT.exr
#   blender -b --factory-startup --python tools/blender_relief_check.py -- ASSET.obj OUT.exr noncolor
#
# "noncolor" sets every image to Non-Color first (what the README's "Using the asset" asks for
# OBJ imports). For tests/data/mirrored_chart with the tilted map the TangentHandedness test
# writes to <build>/test-scratch, the expected normal is (+-0.358, -0.894, 0.268) in Blender's
# axes (right / left half).
import bpy, sys
import numpy
if not hasattr(numpy, "bool"):
    numpy.bool = bool  # the Debian glTF importer uses the removed alias
argv = sys.argv[sys.argv.index("--") + 1:]
path, out, mode = argv[0], argv[1], (argv[2] if len(argv) > 2 else "")
bpy.ops.wm.read_factory_settings(use_empty=True)
if path.endswith(".obj"):
    bpy.ops.wm.obj_import(filepath=path)
else:
    bpy.ops.import_scene.gltf(filepath=path)
for img in bpy.data.images:
    print("image", img.name, img.colorspace_settings.name)
    if mode == "noncolor":
        img.colorspace_settings.name = "Non-Color"
for mat in bpy.data.materials:
    if not mat.use_nodes:
        continue
    nt = mat.node_tree
    bsdf = next((n for n in nt.nodes if n.type == "BSDF_PRINCIPLED"), None)
    if bsdf is None:
        continue
    links = bsdf.inputs["Normal"].links
    print("material", mat.name, "normal input linked:", bool(links))
    src = links[0].from_socket if links else None
    va = nt.nodes.new("ShaderNodeVectorMath"); va.operation = "MULTIPLY_ADD"
    va.inputs[1].default_value = (0.5, 0.5, 0.5); va.inputs[2].default_value = (0.5, 0.5, 0.5)
    if src is not None:
        nt.links.new(src, va.inputs[0])
    else:
        geo = nt.nodes.new("ShaderNodeNewGeometry"); nt.links.new(geo.outputs["Normal"], va.inputs[0])
    em = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(va.outputs[0], em.inputs["Color"])
    outn = next(n for n in nt.nodes if n.type == "OUTPUT_MATERIAL")
    nt.links.new(em.outputs[0], outn.inputs["Surface"])
scene = bpy.context.scene
cam_data = bpy.data.cameras.new("cam"); cam_data.type = "ORTHO"; cam_data.ortho_scale = 2.5
cam = bpy.data.objects.new("cam", cam_data); scene.collection.objects.link(cam)
cam.location = (0, -5, 0); cam.rotation_euler = (1.5707963, 0, 0); scene.camera = cam
scene.render.engine = "CYCLES"; scene.cycles.samples = 1; scene.cycles.device = "CPU"
scene.cycles.use_denoising = False
scene.render.resolution_x = scene.render.resolution_y = 64
scene.view_settings.view_transform = "Standard"
scene.render.image_settings.file_format = "OPEN_EXR"; scene.render.image_settings.color_depth = "32"
scene.render.filepath = out
bpy.ops.render.render(write_still=True)
img = bpy.data.images.load(out)
px = list(img.pixels); w, h = img.size
for name, xs in (("left", range(10, w // 2 - 4)), ("right", range(w // 2 + 4, w - 10))):
    acc = [0.0, 0.0, 0.0]; n = 0
    for y in range(8, h - 8):
        for x in xs:
            i = 4 * (y * w + x)
            if px[i + 3] < 0.999:
                continue
            for c in range(3):
                acc[c] += px[i + c] * 2 - 1
            n += 1
    print("RESULT", name, n, ["%.3f" % (a / max(n, 1)) for a in acc])
