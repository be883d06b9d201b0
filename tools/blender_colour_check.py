# By-hand check of the `color_space` setting against Blender (not run by CI; Blender 3.4 from
# Debian). Writes a plane OBJ with a 2x2 8-bit albedo texture (map_Kd, which Blender marks sRGB
# as it does glTF's baseColorTexture) into FOLDER, lights it like tdf's `lambertian` pass
# (uniform world of radiance `ambient` + a sun with n.l = 0.5 carrying (1 - ambient), pure
# Diffuse BSDF, Standard view transform), renders it with Cycles and prints, per texel, Blender's
# displayed colour beside tdf's `lit_color` in `srgb` and `raw` (shading.h).
#
#   blender -b --factory-startup --python tools/blender_colour_check.py -- FOLDER
import bpy, math, os, struct, sys, zlib

folder = sys.argv[sys.argv.index("--") + 1]
os.makedirs(folder, exist_ok=True)
ambient, cosine = 0.1, 0.5
shade = ambient + (1 - ambient) * cosine
levels = [[(51, 127, 204), (229, 25, 102)], [(127, 127, 127), (12, 178, 76)]]  # rows top to bottom


def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


rows = b"".join(b"\x00" + bytes(c for texel in row for c in texel) for row in levels)
with open(os.path.join(folder, "albedo.png"), "wb") as f:
    f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 2, 2, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))
with open(os.path.join(folder, "plane.mtl"), "w") as f:
    f.write("newmtl m\nKd 1 1 1\nmap_Kd albedo.png\n")
with open(os.path.join(folder, "plane.obj"), "w") as f:
    f.write("mtllib plane.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
            "usemtl m\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.obj_import(filepath=os.path.join(folder, "plane.obj"))
for mat in bpy.data.materials:
    nt = mat.node_tree
    bsdf = next(n for n in nt.nodes if n.type == "BSDF_PRINCIPLED")
    texture = bsdf.inputs["Base Color"].links[0].from_socket
    texture.node.interpolation = "Closest"
    print("albedo image colour space:", texture.node.image.colorspace_settings.name)
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    nt.links.new(texture, diffuse.inputs["Color"])
    nt.links.new(diffuse.outputs[0], next(n for n in nt.nodes if n.type == "OUTPUT_MATERIAL").inputs["Surface"])
scene = bpy.context.scene
world = bpy.data.worlds.new("world")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs[0].default_value = (ambient, ambient, ambient, 1)
scene.world = world
sun = bpy.data.lights.new("sun", "SUN")
sun.energy = (1 - ambient) * math.pi  # irradiance: diffuse radiance = albedo (1 - ambient) n.l
sun.angle = 0
sun_object = bpy.data.objects.new("sun", sun)
scene.collection.objects.link(sun_object)
sun_object.rotation_euler = (math.radians(90) + math.acos(cosine), 0, 0)  # the plane faces -Y in Blender
camera_data = bpy.data.cameras.new("camera")
camera_data.type = "ORTHO"
camera_data.ortho_scale = 2.0
camera = bpy.data.objects.new("camera", camera_data)
scene.collection.objects.link(camera)
camera.location = (0, -5, 0)
camera.rotation_euler = (math.pi / 2, 0, 0)
scene.camera = camera
scene.render.engine = "CYCLES"
scene.cycles.samples = 512
scene.cycles.use_denoising = False
scene.render.resolution_x = scene.render.resolution_y = 16
scene.view_settings.view_transform = "Standard"
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.render.filepath = os.path.join(folder, "render.exr")
bpy.ops.render.render(write_still=True)
image = bpy.data.images.load(scene.render.filepath)
pixels, width = list(image.pixels), image.size[0]


def encode(c):
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def decode(c):
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


worst_srgb = worst_raw = 0.0
for (x, y), (row, column) in (((4, 11), (0, 0)), ((11, 11), (0, 1)), ((4, 4), (1, 0)), ((11, 4), (1, 1))):
    stored = [level / 255 for level in levels[row][column]]
    blender = [encode(max(0.0, pixels[4 * (y * width + x) + c])) for c in range(3)]
    srgb = [encode(min(1.0, decode(c) * shade)) for c in stored]
    raw = [min(1.0, c * shade) for c in stored]
    worst_srgb = max(worst_srgb, max(abs(a - b) for a, b in zip(blender, srgb)))
    worst_raw = max(worst_raw, max(abs(a - b) for a, b in zip(blender, raw)))
    print("texel", levels[row][column], "blender", ["%.4f" % c for c in blender], "srgb", ["%.4f" % c for c in srgb],
          "raw", ["%.4f" % c for c in raw])
print("largest difference to Blender: srgb %.4f (%.2f levels), raw %.4f (%.1f levels)" %
      (worst_srgb, 255 * worst_srgb, worst_raw, 255 * worst_raw))
