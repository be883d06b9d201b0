#pragma once
// scenes/two_part_sphere with four (or N) parts (shared by the train tests and bench/parts_bench.cpp):
// face_labels in four bands of the OBJ's face order (bands that end along chart borders: the
// configuration that measured a 2.83-texel bleed before the part blend ignored the gutter), the
// scene's two tactile maps alternating at repeats 2, 3, 4 and 5. Parts are named band0..band3.
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/scene/scene_file.h>

#include <fstream>
#include <string>

namespace tdf::test {

/// Writes the face label file to `label_file` and returns the scene with `bands` parts (bands
/// of the face order, named band0.., the scene's two maps alternating at repeats 2, 3, ...).
inline SceneDescription banded_sphere(const SceneDescription& two_parts, const TriangleMesh& mesh,
                                      const std::string& label_file, int bands) {
    {
        std::ofstream out(label_file);
        const std::size_t faces = mesh.triangles.size();
        for (std::size_t f = 0; f < faces; ++f) out << "band" << std::size_t(bands) * f / faces << "\n";
    }
    SceneDescription d = two_parts;
    d.parts.source = PartsSourceSpec{};
    d.parts.source.kind = "face_labels";
    d.parts.source.file = label_file;
    d.parts.parts.clear();
    for (int k = 0; k < bands; ++k) {
        PartSpec p = two_parts.parts.parts[std::size_t(k % 2)];
        p.name = "band" + std::to_string(k);
        p.select = {p.name};
        p.layout.repeat = float(2 + k);
        d.parts.parts.push_back(p);
    }
    return d;
}

/// The four-band scene (the configuration of the 2.83-texel bleed before the gutter fix).
inline SceneDescription four_part_sphere(const SceneDescription& two_parts, const TriangleMesh& mesh,
                                         const std::string& label_file) {
    return banded_sphere(two_parts, mesh, label_file, 4);
}

}  // namespace tdf::test
