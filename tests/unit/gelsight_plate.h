#pragma once
// A test asset for the virtual GelSight (issue 24), shared by the render and CLI tests.
#include <fmt/format.h>
#include <tdf/core/atomic_file.h>
#include <tdf/tactile/height_map.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace tdf::test {

// A flat square plate of 1 x 1 mesh units (z = 0, normal +z, UV = xy) and a height map of
// h = amplitude sin(2 pi x / wavelength) in mm at `mm_per_unit`, written as tdf optimize writes
// an asset: <folder>/plate.obj + .mtl with its disp line, plate_height.exr in mm.
inline void write_plate(const std::string& folder, float mm_per_unit, double amplitude_mm, double wavelength_mm) {
    std::filesystem::remove_all(folder);
    std::filesystem::create_directories(folder);
    const int size = 1024;
    HeightMap map;
    map.height = Image(size, size, 1);
    map.mm_per_pixel = mm_per_unit / float(size);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            map.height.at(x, y, 0) = float(amplitude_mm * std::sin(2 * 3.14159265358979323846 * (x + 0.5) * map.mm_per_pixel / wavelength_mm));
    write_height_map(folder + "/plate_height.exr", map);
    write_text_atomically(folder + "/plate.obj",
                          "mtllib plate.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                          "usemtl m\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
    const double range = 2 * amplitude_mm;
    write_text_atomically(folder + "/plate.mtl", fmt::format("newmtl m\ndisp -mm {} {} plate_height.png\n",
                                                             -amplitude_mm / mm_per_unit, range / mm_per_unit));
}

}  // namespace tdf::test
