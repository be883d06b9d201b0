// Writes the two synthetic tactile inputs of issue 28 (tests/unit/tactile_unseen_inputs.h) as
// files, to run `tdf tactile convert` and the measurement script on them:
//
//   tdf_make_tactile_unseen_inputs <folder> [period]   write gentle_veneer_normal.png (1024 px,
//       8-bit RGB, OpenGL) and knit_capture.npy (240x320 float64 mm, loops `period` px apart, 10)
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/normal_map.h>

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "unit/tactile_unseen_inputs.h"

int main(int argc, char** argv) {
    const float period = argc == 3 ? std::strtof(argv[2], nullptr) : 10.0f;
    if (argc < 2 || argc > 3 || !(period >= 4.0f && period <= 40.0f)) {
        std::fprintf(stderr, "usage: tdf_make_tactile_unseen_inputs <folder> [knit loop period, 4-40 px]\n");
        return 2;
    }
    try {
        const std::string folder = argv[1];
        std::filesystem::create_directories(folder);
        tdf::write_png(folder + "/gentle_veneer_normal.png",
                       tdf::encode_normals(tdf::test::gentle_veneer_normals()),
                       8,
                       tdf::Quantize::Truncate);
        tdf::test::write_npy_f8(folder + "/knit_capture.npy", tdf::test::knit_capture_heights(period));
        fmt::print("wrote {0}/gentle_veneer_normal.png and {0}/knit_capture.npy\n", folder);
    } catch (const tdf::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
