// A protocol test program for the `external` parts source (docs/parts-protocol.md, tdf-parts/1):
// no model, a fixed rule so the plumbing is tested end to end. For every view it writes part 0's
// mask where the render is greener than it is red, part 1's elsewhere (inside the coverage mask).
//   tdf_test_segmenter <request.json>          normal run
//   tdf_test_segmenter --fail <request.json>   exit 3 with a message on stderr
//   tdf_test_segmenter --skip <request.json>   write nothing (missing outputs)
#include <tdf/core/config.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
    using namespace tdf;
    try {
        std::string mode, request;
        for (int i = 1; i < argc; ++i) {
            const std::string a = argv[i];
            if (a == "--fail" || a == "--skip")
                mode = a;
            else
                request = a;
        }
        if (mode == "--fail") {
            std::fprintf(stderr, "segmenter: failing on purpose\n");
            return 3;
        }
        const Json r = load_json_file(request);
        if (r.at("protocol") != "tdf-parts/1") return 4;
        if (mode == "--skip") return 0;
        const std::string folder = r.at("folder").get<std::string>();
        for (const Json& view : r.at("images")) {
            const Image input = read_image(folder + "/" + view.at("input").get<std::string>());
            const Image mask = read_image(folder + "/" + view.at("mask").get<std::string>());
            const Json& outputs = view.at("outputs");
            for (std::size_t p = 0; p < outputs.size(); ++p) {
                Image out(input.width(), input.height(), 1, 0.f);
                for (int y = 0; y < input.height(); ++y)
                    for (int x = 0; x < input.width(); ++x) {
                        if (mask.at(x, y, 0) < 0.5f) continue;
                        const bool green = input.at(x, y, 1) > input.at(x, y, 0);
                        out.at(x, y, 0) = (green == (p == 0)) ? 1.f : 0.f;
                    }
                write_png(folder + "/" + outputs[p].get<std::string>(), out);
            }
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "segmenter: %s\n", e.what());
        return 1;
    }
}
